// clothbake report compression FABRIC.toml -o DIR [--resolution N] [--clusters LIST]
// [--ranks LIST] [--targets LIST] [--samples N] [--no-raw] [--no-plots] [--json]
//
// Sweeps the C-PCA compression of the fabric's specular Integral-Radiance tables over clusters,
// ranks and target errors (clothbake's per-texel layout), against the raw tables
// (compress/compression_report.hpp), and writes
//   DIR/compression.csv   one row per setting (the primary output),
//   DIR/compression.json  the same rows plus the inputs of the sweep,
//   DIR/compression_*.png / .svg  size against footprint error and error against decode time
//                         (scripts/plot_compression.py, python3-matplotlib, run as a subprocess on
//                         the CSV; a failure to plot is a warning, the CSV stays).
// Visibility clusters come from the bake's own stages (visibility, cluster;
// bake/reports/compression_data.hpp). The paper's whole-SAT layout is a study outside the product
// (benchmarks/compress/sat_layout_study.cpp, docs/compression.md).
// Files are written to a temporary directory next to DIR and moved into place at the end.
// Exit codes: 0, 1 usage, 2 bad fabric or unwritable output.
//
// One subcommand per report, each with its own options:
//   clothbake report error-time SCENE -o DIR ...  report_error_time.hpp (docs/rendering.md)
//   clothbake report plan SCENE -o DIR ...        report_plan.hpp (docs/scene-plans.md)
//   clothbake report stability -o DIR [--large] [--json]: report_stability.hpp (exit 5 when a
//   row fails, after writing DIR/stability.csv and .json).
#include <fmt/format.h>

#include <array>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <type_traits>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/reports/compression_data.hpp"
#include "bake/reports/report_error_time.hpp"
#include "bake/reports/report_plan.hpp"
#include "bake/reports/report_stability.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compression_report.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::cli {
namespace {

namespace fs = std::filesystem;

struct ReportCliOptions {
  std::string fabric, output;
  std::optional<int> resolution;
  std::string clusters = "1,2,4", ranks = "2,4,8,16,32", targets = "0.03,0.02,0.01,0.008,0.005";
  int samples = 300;
  bool no_raw = false, no_plots = false, json = false;
};

// --clusters, --ranks (whole numbers) and --targets: positive numbers, comma-separated.
template <class T>
std::vector<T> positive_list(const std::string& text, const std::string& option) {
  const bool integers = std::is_integral_v<T>;
  const std::vector<double> values =
      parse_number_list(text, option,
                        {.expected = integers ? "a comma-separated list of positive integers"
                                              : "a comma-separated list of positive numbers",
                         .integers = integers,
                         .positive = true,
                         .max = integers ? double(std::numeric_limits<int>::max()) : 1e308});
  return std::vector<T>(values.begin(), values.end());
}

// Prints a report's JSON document (--json) or its summary; exit 0, or exit 5 with its failure
// after printing.
int print_report(const reports::ReportOutput& report, bool json) {
  if (json)
    print_json(report.doc);
  else
    std::fputs(report.summary.c_str(), stdout);
  if (report.failure) throw Error(ExitCode::VerificationFailed, *report.failure);
  return 0;
}

// The sweep of `report compression` (its options: ReportCliOptions).
int run_compression_report(const ReportCliOptions& o);

// What the reports that render a scene (error-time, plan) share: SCENE, -o, --reference-spp (its
// default `reference_spp` as given), --seed and --image-size W,H (parsed when the report runs).
void add_scene_report_options(CLI::App& sub, std::string& scene, std::string& output,
                              uint32_t& reference_spp, uint64_t& seed, std::string& image_size) {
  sub.add_option("SCENE", scene, "the scene (.toml, docs/scene-format.md)")->required();
  sub.add_option("-o,--output", output, "output directory (created; other files kept)")->required();
  sub.add_option("--reference-spp", reference_spp,
                 "light samples of the reference when the scene has environment lights (default " +
                     std::to_string(reference_spp) + ")");
  sub.add_option("--seed", seed, "seed of the renders (default 1)");
  sub.add_option("--image-size", image_size,
                 "W,H: render at W x H pixels instead of the scene camera's resolution");
}

// `report` has one subcommand per report, each with its own options (docs/cli.md).
Action setup_report(CLI::App& app) {
  app.require_subcommand(1);
  // compression
  auto o = std::make_shared<ReportCliOptions>();
  auto* compression = app.add_subcommand(
      "compression",
      "C-PCA compression of a fabric's specular tables over clusters, ranks and target errors "
      "against the raw tables: size against error and decode time (docs/compression.md)");
  compression->add_option("FABRIC", o->fabric, "the fabric description (.toml)")->required();
  compression->add_option("-o,--output", o->output, "output directory (created; other files kept)")
      ->required();
  compression
      ->add_option("--resolution", o->resolution, "texels per tile side (default: the fabric's)")
      ->check(CLI::Range(kMinResolution, 1024));
  compression->add_option("--clusters", o->clusters,
                          "C-PCA clusters per visibility cluster (default 1,2,4)");
  compression->add_option("--ranks", o->ranks, "fixed ranks (default 2,4,8,16,32)");
  compression->add_option("--targets", o->targets,
                          "target relative RMS texel errors (default 0.03,0.02,0.01,0.008,0.005)");
  compression->add_option("--samples", o->samples, "footprints per size (default 300)")
      ->check(CLI::Range(10, 100000));
  compression->add_flag("--no-raw", o->no_raw,
                        "skip the raw tables (built in memory: 2 GiB at 256^2)");
  compression->add_flag("--no-plots", o->no_plots, "write the CSV and JSON only");
  add_json_flag(*compression, o->json, "print the rows as JSON on stdout");

  // error-time
  auto et = std::make_shared<reports::ErrorTimeOptions>();
  auto json = std::make_shared<bool>(false);                     // --json of whichever report runs
  auto et_cli = std::make_shared<std::array<std::string, 3>>();  // methods, spp, image size
  (*et_cli)[0] = "multiscale,multiscale-paper,brute,brute-path";
  (*et_cli)[1] = "1,2,4,8,16,32,64,128,256";
  auto* error_time = app.add_subcommand(
      "error-time",
      "error against run time of the evaluator's methods on a scene, against its path-traced truth "
      "and its exact footprint reference (docs/rendering.md)");
  add_scene_report_options(*error_time, et->scene, et->output, et->reference_spp, et->seed,
                           (*et_cli)[2]);
  error_time->add_option("--methods", (*et_cli)[0],
                         "methods to compare (default " + (*et_cli)[0] + ")");
  error_time->add_option("--spp", (*et_cli)[1], "spp sweep (default " + (*et_cli)[1] + ")");
  error_time->add_option("--cache", et->cache, "asset and reference cache folder");
  error_time->add_option("--truth-spp", et->truth_spp,
                         "spp of the path-traced truth (brute-path, two halves; even; 0 skips "
                         "it; default 1024)");
  error_time->add_flag("--raw-tables", et->raw_tables,
                       "also render the multi-scale methods with the raw and the compressed tables "
                       "(fabrics baked with --keep-raw into the cache: 2 GB for a 256^2 twill)");
  error_time->add_flag("--near-field", et->near_field,
                       "also ray-trace the first cloth plane's relief and compare the model with "
                       "and without parallax offsets against it");
  error_time->add_flag("--no-plots", et->no_plots, "write the CSV and JSON only");
  add_json_flag(*error_time, *json, "print the rows as JSON on stdout");

  // plan
  auto po = std::make_shared<reports::PlanReportOptions>();
  po->spp = 2;
  po->reference_spp = 64;
  auto plan_size = std::make_shared<std::string>();
  auto* plan = app.add_subcommand(
      "plan",
      "a scene rendered with fully baked and with scene-planned assets, against its reference "
      "(docs/scene-plans.md)");
  add_scene_report_options(*plan, po->scene, po->output, po->reference_spp, po->seed, *plan_size);
  plan->add_option("--spp", po->spp, "samples per pixel of the two renders (default 2)")
      ->check(CLI::Range(1u, 1u << 20));
  add_json_flag(*plan, *json, "print the report as JSON on stdout");

  // stability
  auto so = std::make_shared<reports::StabilityOptions>();
  auto* stability = app.add_subcommand(
      "stability",
      "the model and baked queries at the edges of the accepted inputs against direct "
      "computations (docs/hardening.md)");
  stability->add_option("-o,--output", so->output, "output directory (created)")->required();
  stability->add_flag("--large", so->large,
                      "bake the table case at 2048^2 instead of 256^2 (minutes, ~2 GB)");
  add_json_flag(*stability, *json, "print the rows as JSON on stdout");

  return [o, et, et_cli, po, plan_size, so, json, error_time, plan, stability] {
    if (stability->parsed()) return print_report(reports::stability_report(*so), *json);
    if (plan->parsed()) {
      if (!plan_size->empty()) {
        const std::array<int, 2> wh = parse_image_size(*plan_size);
        po->width = wh[0];
        po->height = wh[1];
      }
      return print_report(reports::plan_report(*po), *json);
    }
    if (error_time->parsed()) {
      if (!(*et_cli)[2].empty()) {
        const std::array<int, 2> wh = parse_image_size((*et_cli)[2]);
        et->width = wh[0];
        et->height = wh[1];
      }
      et->methods.clear();
      std::stringstream in((*et_cli)[0]);
      for (std::string item; std::getline(in, item, ',');)
        et->methods.push_back(item);
      et->spp.clear();
      for (int v : positive_list<int>((*et_cli)[1], "--spp"))
        et->spp.push_back(uint32_t(v));
      et->quiet = *json;
      return print_report(reports::error_time_report(*et), *json);
    }
    return run_compression_report(*o);
  };
}

int run_compression_report(const ReportCliOptions& o) {
  compress::ReportOptions options;
  options.clusters = positive_list<int>(o.clusters, "--clusters");
  options.ranks = positive_list<int>(o.ranks, "--ranks");
  options.targets = positive_list<double>(o.targets, "--targets");
  options.samples = o.samples;
  options.raw = !o.no_raw;
  const fs::path out(o.output);
  if (fs::exists(out) && !fs::is_directory(out))
    throw_input_error(o.output + ": exists and is not a directory");

  const auto full = reports::load_compression_data(o.fabric, o.resolution);
  options.seed = full->fabric.bake.seed;
  compress::RawTablesBuilder raw_builder = [&]() {
    tables::RadianceOptions ro;
    ro.bins_per_side = full->data.bins_per_side;
    ro.samples_per_side = full->data.samples_per_bin_side;
    ro.warn_unresolved = false;
    std::vector<formats::Section> sections =
        tables::radiance_sections(tables::build_specular_tables(full->inputs.view, ro));
    return formats::serialize_asset(sections);
  };
  const auto rows = compress::compression_sweep(
      full->data, options, raw_builder, [](int done, int total, const std::string& label) {
        info(fmt::format("report: [{}/{}] {}", done, total, label));
      });

  // Write into a temporary directory, then move the files into place.
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  const fs::path tmp = parent / (out.filename().string() + ".tmp-report");
  std::error_code ec;
  fs::remove_all(tmp, ec);
  if (!fs::create_directories(tmp, ec) && ec)
    throw_input_error(tmp.string() + ": cannot create: " + ec.message());
  const std::string csv = compress::report_csv(rows, compress::report_sides(full->data.resolution));
  nlohmann::json doc;
  doc["fabric"] = o.fabric;
  doc["resolution"] = full->data.resolution;
  doc["bins_per_side"] = full->data.bins_per_side;
  doc["clusters"] = full->clusters;
  doc["cluster_source"] = full->label_source;
  doc["footprint_sides"] = {"1", "2", "4", "8", "16", "64", "tile", "3 tiles"};
  nlohmann::json jrows = nlohmann::json::array();
  for (const auto& r : rows)
    jrows.push_back({{"layout", r.layout},
                     {"normalisation", r.normalisation},
                     {"mode", r.mode},
                     {"resolution", r.resolution},
                     {"clusters", r.clusters},
                     {"rank", r.rank},
                     {"target", r.target},
                     {"images", r.images},
                     {"stored_bytes", r.stored_bytes},
                     {"raw_float_bytes", r.raw_float_bytes},
                     {"ratio", r.ratio},
                     {"decoded_bytes", r.decoded_bytes},
                     {"texel_error", r.texel_error},
                     {"normalised_mse", r.normalised_mse},
                     {"footprint_error", r.footprint_error},
                     {"query_ns", r.query_ns},
                     {"compress_cpu_seconds", r.compress_cpu_seconds},
                     {"compress_wall_seconds", r.compress_wall_seconds},
                     {"paper_point", r.paper_point}});
  doc["rows"] = jrows;
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream f(tmp / name, std::ios::binary);
    f << text;
    f.close();
    if (!f) throw_input_error((tmp / name).string() + ": cannot write");
  };
  write("compression.csv", csv);
  write("compression.json",
        doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  std::vector<std::string> plots;
  if (!o.no_plots) {
    // $CLOTHBAKE_PLOT_SCRIPT, else the source tree this file was compiled from.
    const char* env = std::getenv("CLOTHBAKE_PLOT_SCRIPT");
    const fs::path script =
        env ? fs::path(env) : fs::path(CLOTHBAKE_SOURCE_DIR) / "scripts" / "plot_compression.py";
    // Debian's interpreter (python3-matplotlib) when present, else whatever python3 is.
    const std::string python =
        fs::exists("/usr/bin/python3") ? std::string("/usr/bin/python3") : std::string("python3");
    const std::string command = python + " '" + script.string() + "' '" +
                                (tmp / "compression.csv").string() + "' '" + tmp.string() +
                                "' > /dev/null";
    if (!fs::exists(script) || std::system(command.c_str()) != 0)
      warn("report: plotting failed (python3-matplotlib missing?); the CSV is written");
  }
  fs::create_directories(out, ec);
  for (const auto& entry : fs::directory_iterator(tmp)) {
    fs::rename(entry.path(), out / entry.path().filename(), ec);
    if (ec) throw_input_error((out / entry.path().filename()).string() + ": " + ec.message());
    plots.push_back((out / entry.path().filename()).string());
  }
  fs::remove_all(tmp, ec);
  if (o.json) {
    doc["files"] = plots;
    doc["warnings"] = take_warnings();
    print_json(doc);
  } else {
    std::cout << csv;
  }
  return 0;
}

const bool report_registered = register_command(
    {"report",
     "write a report as CSV, JSON and plots: compression, error-time, plan or stability (clothbake "
     "report REPORT --help lists each one's options)",
     setup_report});

}  // namespace
}  // namespace clothbake::cli

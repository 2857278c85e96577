// Study of the paper's whole-SAT C-PCA layout (Sec. 4.4; sat_pca.hpp, sat_normalise.hpp) against
// clothbake's per-texel layout at the same reduced resolution (docs/compression.md, "The paper's
// whole-SAT layout"). clothbake does not store the paper's layout; this program keeps the
// comparison that decided it reproducible.
//
//   sat_layout_study FABRIC.toml [-o CSV] [--resolution N] [--samples N]
//
// One fabric's specular tables at N texels per side (default 64: the layout holds C x B x N^2
// floats while fitting), with the bake's own visibility clusters
// (bake/reports/compression_data.hpp) and the fabric's [bake] seed. Rows, in the CSV columns of
// `clothbake report compression` (compress::report_csv), written to CSV or stdout:
//  - layout "texel" at target errors 2 % and 0.8 % (compress::texel_row), for comparison;
//  - layout "sat" with normalisation none / plane / plane+unit for (k, r) = (4, 10), (1, 10),
//    (4, 20), (1, 40), (8, 10); the paper's operating point (plane+unit, k = 4, r = 10) has
//    paper_point = 1. Queries through the unoptimised in-memory model, timed on a tenth of the
//    texel rows' timing queries.
// Every row is measured on the same footprints (compress::report_probes, seed + 1) as the report
// measures its rows. scripts/plot_compression.py CSV DIR plots the CSV (the paper's point marked).
// Progress on stderr. Exit codes: 0, 1 usage, 2 bad fabric or unwritable output.
//
// Not part of the product.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "bake/reports/compression_data.hpp"
#include "benchmarks/compress/sat_pca.hpp"
#include "common/error.hpp"
#include "compress/compression_report.hpp"

using namespace clothbake;

namespace {

struct StudyOptions {
  std::string fabric, output;
  int resolution = 64;
  int samples = 300;
};

std::vector<compress::ReportRow> study_rows(const compress::DirectionalTexels& data,
                                            const StudyOptions& o, uint64_t seed) {
  const std::vector<double> texel_targets = {0.02, 0.008};
  const std::vector<std::pair<int, int>> sat_shapes = {{4, 10}, {1, 10}, {4, 20}, {1, 40}, {8, 10}};
  const compress::SatNormalisation modes[] = {compress::SatNormalisation::None,
                                              compress::SatNormalisation::Plane,
                                              compress::SatNormalisation::PlaneUnit};
  compress::ReportOptions options;
  options.samples = o.samples;
  options.seed = seed;
  const std::size_t total = texel_targets.size() + std::size(modes) * sat_shapes.size();
  std::size_t done = 0;
  auto step = [&](const std::string& label) {
    std::fprintf(stderr, "sat_layout_study: [%zu/%zu] %s\n", done++, total, label.c_str());
  };
  const compress::ReportProbes probes = compress::report_probes(data, o.samples, seed + 1);
  std::vector<compress::ReportRow> rows;
  for (double target : texel_targets) {
    step("texel target " + std::to_string(target));
    compress::CpcaOptions cpca;
    cpca.rank = 64;
    cpca.target_error = target;
    cpca.seed = seed;
    rows.push_back(compress::texel_row(data, cpca, probes, options));
  }
  for (compress::SatNormalisation mode : modes)
    for (const auto& [k, r] : sat_shapes) {
      const std::string name = compress::sat_normalisation_name(mode);
      step("sat " + name + " k=" + std::to_string(k) + " r=" + std::to_string(r));
      compress::SatPcaOptions so;
      so.clusters = k;
      so.rank = r;
      so.normalisation = mode;
      so.seed = seed;
      compress::ReportRow row;
      compress::SatPcaModel model;
      compress::time_compression([&] { model = compress::SatPcaModel::fit(data, so); }, &row);
      row.layout = "sat";
      row.normalisation = name;
      row.mode = "fixed";
      row.resolution = data.resolution;
      row.clusters = k;
      row.rank = r;
      row.images = model.groups() * (1 + r);
      row.stored_bytes = model.stored_bytes();
      row.raw_float_bytes = compress::raw_float_bytes(data);
      row.ratio = row.stored_bytes ? double(row.raw_float_bytes) / double(row.stored_bytes) : 0;
      row.normalised_mse = model.normalised_mse();
      row.paper_point = mode == compress::SatNormalisation::PlaneUnit && k == 4 && r == 10;
      compress::measure_queries(
          data, probes,
          [&](const reader::Footprint& rect, const double* h, double* out) {
            for (int c = 0; c < data.cluster_count; ++c)
              if (!model.query(rect, h, c, &out[c])) return false;
            return true;
          },
          options.timing_queries / 10, seed, &row);
      rows.push_back(std::move(row));
    }
  std::fprintf(stderr, "sat_layout_study: [%zu/%zu] done\n", total, total);
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  StudyOptions o;
  CLI::App app{
      "The paper's whole-SAT C-PCA layout against clothbake's per-texel layout at one "
      "reduced resolution (docs/compression.md)",
      "sat_layout_study"};
  app.add_option("FABRIC", o.fabric, "the fabric description (.toml)")->required();
  app.add_option("-o,--output", o.output, "CSV file to write (default: stdout)");
  app.add_option("--resolution", o.resolution,
                 "texels per tile side (default 64; the layout holds clusters x bins x N^2 floats)")
      ->check(CLI::Range(8, 256));
  app.add_option("--samples", o.samples, "footprints per size (default 300)")
      ->check(CLI::Range(10, 100000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // --help on stdout, an error on stderr
    return code == 0 ? 0 : int(ExitCode::Usage);
  }
  try {
    const auto loaded = reports::load_compression_data(o.fabric, o.resolution);
    const auto rows = study_rows(loaded->data, o, loaded->fabric.bake.seed);
    const std::string csv =
        compress::report_csv(rows, compress::report_sides(loaded->data.resolution));
    if (o.output.empty()) {
      std::cout << csv;
      return 0;
    }
    std::ofstream f(o.output, std::ios::binary);
    f << csv;
    f.close();
    if (!f) throw Error(ExitCode::Input, o.output + ": cannot write");
    return 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "sat_layout_study: %s\n", e.what());
    return int(e.code());
  }
}

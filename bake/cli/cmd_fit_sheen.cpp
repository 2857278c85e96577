// clothbake fit-sheen [--convention published|converged] [-o model/sheen_table.hpp] [--samples N]
// [--resolution COS,ROUGH] [--seed S] [--threads T] [--json]: simulate the volumetric sheen layer
// of Zeltner et al. 2022 by Monte Carlo at every (cos theta_o, roughness) node under the
// convention's rules (published, the default: paths cut after 16 scattering events as in their
// published table; converged: every path followed to the end) and fit one LTC lobe per node; write
// the table as the C++ header that model/sheen.hpp includes (docs/sheen.md). Deterministic for the
// same options, whatever the thread count. Without -o the header goes to stdout (unless --json).
#include <tbb/global_control.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "formats/writer/atomic_file.hpp"
#include "model/parameter_text.hpp"
#include "sheen/sheen_fit.hpp"
#include "sheen/sheen_table_writer.hpp"

namespace clothbake::cli {
namespace {

struct FitSheenOptions {
  std::string convention = "published";
  std::string output;
  uint64_t samples = 500000;
  std::string resolution = "32,32";
  uint64_t seed = 1;
  int threads = 0;
  bool json = false;
};

// "C,R" -> two integers; throws CLI::ValidationError naming the option.
std::pair<int, int> parse_resolution(const std::string& text) {
  const auto v = parse_number_list(text, "--resolution",
                                   {.expected = "COS,ROUGH with two integers in [2, 1024]",
                                    .count = 2,
                                    .integers = true,
                                    .min = 2,
                                    .max = 1024});
  return {int(v[0]), int(v[1])};
}

nlohmann::json fit_json(const sheen::SheenTableFit& fit, const std::string& output) {
  nlohmann::json nodes = nlohmann::json::array();
  double max_l1 = 0.0, max_excess = 0.0, max_se = 0.0;
  int inherited = 0;
  uint64_t truncated = 0;
  for (const sheen::SheenTableNode& n : fit.nodes) {
    nodes.push_back({{"cos_theta", n.cos_theta},
                     {"roughness", n.roughness},
                     {"simulated_cos", n.simulated_cos},
                     {"simulated_roughness", n.simulated_roughness},
                     {"a", n.a},
                     {"b", n.b},
                     {"albedo", n.albedo},
                     {"albedo_standard_error", n.albedo_standard_error},
                     {"reflected_paths", n.reflected},
                     {"truncated_paths", n.truncated},
                     {"mean_scattering_order", n.mean_scattering_order},
                     {"l1_error", n.l1_error},
                     {"noise_l1", n.noise_l1},
                     {"inherited_shape", n.inherited_shape}});
    if (n.inherited_shape) {
      ++inherited;
    } else {
      max_l1 = std::max(max_l1, n.l1_error);
      max_excess = std::max(max_excess, n.l1_error - n.noise_l1);
    }
    max_se = std::max(max_se, n.albedo_standard_error);
    truncated += n.truncated;
  }
  const auto& s = fit.settings;
  return {{"output", output.empty() ? nlohmann::json(nullptr) : nlohmann::json(output)},
          {"convention", model::sheen_convention_name(s.convention)},
          {"max_scattering_order", s.rules().max_order},
          {"classified_by_last_direction", s.rules().classify_by_last_direction},
          {"min_simulated_cos", s.rules().min_cos},
          {"min_simulated_roughness", s.rules().min_roughness},
          {"cos_count", s.cos_count},
          {"roughness_count", s.roughness_count},
          {"paths_per_node", s.paths_per_node},
          {"seed", s.seed},
          {"exit_bins", {s.binning.z_bins, s.binning.phi_bins}},
          {"min_reflected", s.min_reflected},
          {"inherited_shape_nodes", inherited},
          {"max_l1_error", max_l1},
          {"max_l1_above_noise", max_excess},
          {"max_albedo_standard_error", max_se},
          {"truncated_paths", truncated},
          {"simulate_seconds", fit.simulate_seconds},
          {"fit_seconds", fit.fit_seconds},
          {"nodes", nodes},
          {"warnings", take_warnings()}};
}

Action setup_fit_sheen(CLI::App& app) {
  auto o = std::make_shared<FitSheenOptions>();
  app.add_option("--convention", o->convention,
                 "simulation rules: published (Zeltner et al.'s table: paths cut after 16 "
                 "scattering events, classified by their last direction; for "
                 "model/sheen_table.hpp) or converged (every path followed to the end; for "
                 "model/sheen_table_converged.hpp)")
      ->check(CLI::IsMember({"published", "converged"}))
      ->capture_default_str();
  app.add_option("-o,--output", o->output,
                 "header to write (e.g. model/sheen_table.hpp); default: stdout");
  app.add_option("--samples", o->samples, "simulated light paths per table node")
      ->check(CLI::Range(uint64_t(100), uint64_t(1) << 40))
      ->capture_default_str();
  app.add_option("--resolution", o->resolution, "table nodes COS,ROUGH (each 2 to 1024)")
      ->capture_default_str();
  app.add_option("--seed", o->seed, "random seed")->capture_default_str();
  add_threads_option(app, o->threads, "worker threads");
  add_json_flag(app, o->json, "print the fit report as one JSON document on stdout");
  return [o] {
    const auto [cos_count, roughness_count] = parse_resolution(o->resolution);
    if (!o->output.empty()) {
      // Fail before minutes of simulation rather than after (write_text_atomically checks again).
      const std::filesystem::path target(o->output);
      const std::filesystem::path dir = target.has_parent_path() ? target.parent_path() : ".";
      std::error_code ec;
      if (!std::filesystem::is_directory(dir, ec))
        throw_input_error("cannot write '" + o->output + "': directory '" + dir.string() +
                          "' does not exist");
    }
    sheen::SheenFitSettings settings;
    settings.cos_count = cos_count;
    settings.roughness_count = roughness_count;
    settings.paths_per_node = o->samples;
    settings.seed = o->seed;
    model::parse_sheen_convention(o->convention, settings.convention);  // checked by IsMember
    std::optional<tbb::global_control> threads;
    if (o->threads > 0)
      threads.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(o->threads));
    take_warnings();

    std::mutex progress_mutex;
    int last_decile[2] = {0, 0};
    const sheen::SheenTableFit fit =
        sheen::fit_sheen_table(settings, [&](int done, int total, const char* phase) {
          const int decile = done * 10 / total;
          const int p = phase[0] == 's' ? 0 : 1;
          std::lock_guard<std::mutex> lock(progress_mutex);
          if (decile > last_decile[p]) {
            last_decile[p] = decile;
            info(std::string("fit-sheen: ") + phase + " " + std::to_string(decile * 10) + "%");
          }
        });
    // Under the published rules paths are cut on purpose; under the converged ones a cut path is
    // one the table misses.
    for (const sheen::SheenTableNode& n : fit.nodes)
      if (n.truncated > 0 && !settings.rules().classify_by_last_direction)
        warn("fit-sheen: " + std::to_string(n.truncated) + " paths truncated at cos " +
             std::to_string(n.cos_theta) + ", roughness " + std::to_string(n.roughness));
    const std::string header = sheen::format_sheen_table_header(fit);
    if (!o->output.empty()) formats::write_text_atomically(o->output, header);
    info("fit-sheen: simulated in " + std::to_string(fit.simulate_seconds) + " s, fitted in " +
         std::to_string(fit.fit_seconds) + " s");
    if (o->json) {
      print_json(fit_json(fit, o->output));
    } else if (o->output.empty()) {
      std::cout << header;
      std::cout.flush();
    }
    return 0;
  };
}

const bool fit_sheen_registered = register_command(
    {"fit-sheen",
     "Fit the sheen LTC table (model/sheen_table.hpp, or model/sheen_table_converged.hpp with "
     "--convention converged) to a Monte Carlo simulation of the sheen layer",
     setup_fit_sheen});

}  // namespace
}  // namespace clothbake::cli

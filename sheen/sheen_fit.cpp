#include "sheen/sheen_fit.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <stdexcept>

#include "sheen/ltc_fit.hpp"

namespace clothbake::sheen {

void validate(const SheenFitSettings& s) {
  if (s.cos_count < 2 || s.cos_count > 1024)
    throw std::invalid_argument("cos resolution must be 2 to 1024, got " +
                                std::to_string(s.cos_count));
  if (s.roughness_count < 2 || s.roughness_count > 1024)
    throw std::invalid_argument("roughness resolution must be 2 to 1024, got " +
                                std::to_string(s.roughness_count));
  if (s.paths_per_node < 100)
    throw std::invalid_argument("samples per node must be at least 100, got " +
                                std::to_string(s.paths_per_node));
  if (s.binning.z_bins < 2 || s.binning.phi_bins < 2 || s.binning.z_bins > 256 ||
      s.binning.phi_bins > 256)
    throw std::invalid_argument("exit histogram bins must be 2 to 256 per axis");
  if (s.convention != model::SheenConvention::Published &&
      s.convention != model::SheenConvention::Converged)
    throw std::invalid_argument("unknown sheen convention " + std::to_string(int(s.convention)));
}

SheenTableFit fit_sheen_table(const SheenFitSettings& settings,
                              const std::function<void(int, int, const char*)>& progress) {
  validate(settings);
  SheenTableFit fit;
  fit.settings = settings;
  const int nc = settings.cos_count, nr = settings.roughness_count;
  const int total = nc * nr;
  fit.nodes.resize(static_cast<std::size_t>(total));
  std::vector<std::vector<double>> targets(static_cast<std::size_t>(total));
  const SheenSimulationRules rules = settings.rules();

  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  std::atomic<int> done{0};
  tbb::parallel_for(
      tbb::blocked_range<int>(0, total, 1), [&](const tbb::blocked_range<int>& range) {
        for (int index = range.begin(); index != range.end(); ++index) {
          const int i = index % nc, j = index / nc;
          SheenTableNode& node = fit.nodes[std::size_t(index)];
          node.cos_theta = double(i) / (nc - 1);
          node.roughness = double(j) / (nr - 1);
          node.simulated_cos = std::max(node.cos_theta, rules.min_cos);
          node.simulated_roughness = std::max(node.roughness, rules.min_roughness);
          LayerSimulationSettings sim;
          sim.paths = settings.paths_per_node;
          sim.seed = settings.seed;
          sim.stream = uint64_t(index);
          sim.binning = settings.binning;
          const LayerSimulation result = simulate_sheen_layer(
              node.simulated_cos, node.simulated_roughness, with_rules(sim, rules));
          node.albedo = result.albedo();
          node.albedo_standard_error = result.albedo_standard_error();
          node.reflected = result.reflected;
          node.truncated = result.truncated;
          node.mean_scattering_order = double(result.scattering_events) / double(result.paths);
          std::vector<double>& target = targets[std::size_t(index)];
          target.assign(result.exit_counts.size(), 0.0);
          if (result.reflected > 0)
            for (std::size_t k = 0; k < target.size(); ++k)
              target[k] = double(result.exit_counts[k]) / double(result.reflected);
          const int now = ++done;
          if (progress) progress(now, total, "simulate");
        }
      });
  const auto t1 = Clock::now();

  const LtcBinQuadrature quadrature(settings.binning);
  done = 0;
  tbb::parallel_for(tbb::blocked_range<int>(0, nc, 1), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i != range.end(); ++i) {
      bool have_previous = false;
      std::array<double, 2> previous{1.0, 0.0};
      const bool at_pole = (i == nc - 1);  // cos theta_o = 1: rotationally symmetric lobe
      for (int j = nr - 1; j >= 0; --j) {
        const int index = j * nc + i;
        SheenTableNode& node = fit.nodes[std::size_t(index)];
        const std::vector<double>& target = targets[std::size_t(index)];
        if (node.reflected < settings.min_reflected && have_previous) {
          node.a = previous[0];
          node.b = previous[1];
          node.inherited_shape = true;
        } else {
          std::vector<std::array<double, 2>> starts{{1.0, 0.0}};
          if (have_previous) starts.push_back(previous);
          const LtcFit lobe = fit_ltc_lobe(target, quadrature, starts, at_pole);
          node.a = lobe.a;
          node.b = lobe.b;
          node.l1_error = lobe.l1_error;
          node.noise_l1 = expected_noise_l1(target, node.reflected);
          node.evaluations = lobe.evaluations;
          previous = {lobe.a, lobe.b};
          have_previous = true;
        }
        const int now = ++done;
        if (progress) progress(now, total, "fit");
      }
      // The roughest node of a row is always fitted (its R is the largest of the row), even from
      // few reflected paths, so that every inherited shape comes from a fit.
    }
  });
  const auto t2 = Clock::now();
  fit.simulate_seconds = std::chrono::duration<double>(t1 - t0).count();
  fit.fit_seconds = std::chrono::duration<double>(t2 - t1).count();
  return fit;
}

}  // namespace clothbake::sheen

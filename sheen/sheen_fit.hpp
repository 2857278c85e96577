// The sheen LTC table: simulate the sheen layer at every (cos theta_o, roughness) node, then fit
// one LTC lobe per node (docs/sheen.md). Deterministic for the same settings, whatever the number
// of threads: every node has its own random stream, and the fits run per cos theta row in a fixed
// order (from roughness 1 down to 0, each fit starting from the previous node's solution as well
// as from the plain cosine, as in Zeltner et al. 2022, so that the table is smooth).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sheen/sheen_layer.hpp"

namespace clothbake::sheen {

struct SheenFitSettings {
  // Simulation rules (SheenSimulationRules): Published, the rules of Zeltner et al.'s published
  // table (the default, as renderers ship it), or Converged (every path followed to the end).
  model::SheenConvention convention = model::SheenConvention::Published;
  int cos_count = 32;        // nodes cos theta_o = i / (cos_count - 1)
  int roughness_count = 32;  // nodes roughness = j / (roughness_count - 1)
  uint64_t paths_per_node = 500000;
  uint64_t seed = 1;
  ExitBinning binning;  // exit-direction histogram the lobes are fitted to
  // A node whose simulation reflects fewer paths than this keeps the lobe shape (a, b) of its
  // neighbour at the next higher roughness (its R is still the simulated one). Such nodes have
  // R < min_reflected / paths_per_node, so their shape barely matters.
  uint64_t min_reflected = 2000;

  // The rules of `convention`; cos theta_o = 0 is simulated at rules().min_cos (a ray parallel to
  // the layer never enters it; the limit is continuous). Throws for an unknown convention.
  SheenSimulationRules rules() const { return simulation_rules(convention); }
};

// Validates the settings; throws std::invalid_argument naming the offending one.
void validate(const SheenFitSettings& settings);

struct SheenTableNode {
  double cos_theta = 0.0, roughness = 0.0;  // the node
  double simulated_cos = 0.0;               // cos theta_o the layer was simulated at
  double simulated_roughness = 0.0;         // roughness the layer was simulated at
  double a = 1.0, b = 0.0;                  // LTC coefficients
  double albedo = 0.0;                      // R: fraction of reflected paths
  double albedo_standard_error = 0.0;
  uint64_t reflected = 0, truncated = 0;  // truncated: cut at the rules' order cap
  double mean_scattering_order = 0.0;     // scattering events per path
  double l1_error = 0.0;                  // sum_k |p_k - P_k| of the fit (noise included)
  double noise_l1 = 0.0;                  // the part of l1_error expected from noise alone
  bool inherited_shape = false;  // too few reflected paths: (a, b) of the rougher neighbour
  int evaluations = 0;           // Nelder-Mead objective evaluations
};

struct SheenTableFit {
  SheenFitSettings settings;
  std::vector<SheenTableNode> nodes;  // index roughness_index * cos_count + cos_index
  double simulate_seconds = 0.0, fit_seconds = 0.0;

  const SheenTableNode& at(int cos_index, int roughness_index) const {
    return nodes[std::size_t(roughness_index) * std::size_t(settings.cos_count) +
                 std::size_t(cos_index)];
  }
};

// Runs the simulation and the fits, in parallel on the current TBB arena. progress (optional) is
// called from worker threads with (nodes done, nodes total, phase name).
SheenTableFit fit_sheen_table(const SheenFitSettings& settings,
                              const std::function<void(int, int, const char*)>& progress = nullptr);

}  // namespace clothbake::sheen

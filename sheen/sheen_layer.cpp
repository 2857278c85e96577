// Volumetric random walk through the sheen layer (Zeltner et al. 2022, talk and supplementary
// code): unit thickness, density 1, single-scattering albedo 1, SGGX fibre-like specular
// microflakes with S = diag(1, 1, roughness^4). The extinction coefficient is directional,
// sigma_t(d) = density * sigma(d) with the SGGX projected area sigma(d) = sqrt(d^T S d).
//
// A path starts at the top (depth 0) travelling along d = -wo. Each step samples a free-flight
// distance t ~ Exp(sigma_t(d)); the depth changes by t * (-d.z). Leaving depth [0, 1] ends the path
// (top: reflected with exit direction d, bottom: transmitted); otherwise the path scatters into a
// direction drawn exactly from the specular phase function. Because the albedo is 1 every path has
// weight 1: the estimator is analog and unbiased, and exit directions are samples of f cos / R.
//
// Two sets of rules (SheenSimulationRules): the converged ones follow paths until they leave the
// slab (the cap max_order is never reached in practice and truncated paths are reported, not
// counted as reflected); the published ones (Zeltner et al.'s fitting code) cut a path right after
// its 16th scattering event and classify it by that last direction, as their table was made.
#include "sheen/sheen_layer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "sheen/rng.hpp"

namespace clothbake::sheen {

SheenSimulationRules simulation_rules(model::SheenConvention convention) {
  switch (convention) {
    case model::SheenConvention::Published:
      return {16, true, 0.01, 0.01};
    case model::SheenConvention::Converged:
      return {100000, false, 1e-3, 0.0};
  }
  throw std::invalid_argument("sheen layer: unknown convention " + std::to_string(int(convention)));
}

LayerSimulationSettings with_rules(LayerSimulationSettings settings,
                                   const SheenSimulationRules& rules) {
  settings.max_order = rules.max_order;
  settings.classify_by_last_direction = rules.classify_by_last_direction;
  return settings;
}

int ExitBinning::bin_of(const Vec3d& w) const {
  const double z = std::clamp(w.z, 0.0, 1.0);
  const int iz = std::min(int(std::sqrt(z) * z_bins), z_bins - 1);
  const double phi = std::atan2(std::abs(w.y), w.x);  // [0, pi]
  const int iphi = std::clamp(int(phi / kPi * phi_bins), 0, phi_bins - 1);
  return iz * phi_bins + iphi;
}

double LayerSimulation::albedo_standard_error() const {
  if (paths == 0) return 0.0;
  const double r = albedo();
  return std::sqrt(std::max(r * (1.0 - r), 0.0) / double(paths));
}

LayerSimulation simulate_sheen_layer(double cos_theta_o, double roughness,
                                     const LayerSimulationSettings& settings) {
  if (!(cos_theta_o > 0.0 && cos_theta_o <= 1.0))
    throw std::invalid_argument("sheen layer: cos_theta_o = " + std::to_string(cos_theta_o) +
                                " is outside (0, 1]");
  if (!(roughness >= 0.0 && roughness <= 1.0))
    throw std::invalid_argument("sheen layer: roughness = " + std::to_string(roughness) +
                                " is outside [0, 1]");
  if (settings.binning.z_bins < 1 || settings.binning.phi_bins < 1 || settings.max_order < 1)
    throw std::invalid_argument("sheen layer: bins and max_order must be positive");

  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(roughness);
  constexpr double kDensity = 1.0;    // per unit thickness (Zeltner et al.)
  constexpr double kThickness = 1.0;  // depth runs from 0 (top) to 1 (bottom)
  const Vec3d wo{std::sqrt(std::max(0.0, 1.0 - cos_theta_o * cos_theta_o)), 0.0, cos_theta_o};

  LayerSimulation result;
  result.paths = settings.paths;
  if (settings.histogram) result.exit_counts.assign(settings.binning.bin_count(), 0);
  if (flakes.sigma == 0.0) {
    // Roughness 0: every flake normal is horizontal (m.z = 0), so a specular reflection keeps the
    // vertical component of the direction and a path that enters downwards never turns up. The
    // layer reflects nothing: R = 0 exactly (following the paths would only cost ~1 / cos_theta_o
    // scattering events each).
    result.transmitted = settings.paths;
    return result;
  }
  Rng rng(settings.seed, settings.stream);

  for (uint64_t path = 0; path < settings.paths; ++path) {
    Vec3d d = -wo;
    double depth = 0.0;
    int order = 0;
    while (true) {
      const double sigma_t = kDensity * flakes.projected_area(d);
      // 1 - u is in (0, 1], so the log is finite; sigma_t = 0 means free flight to the boundary.
      const double t = sigma_t > 0.0 ? -std::log(1.0 - rng.uniform()) / sigma_t
                                     : std::numeric_limits<double>::infinity();
      depth += t * (-d.z);
      if (depth < 0.0) {
        ++result.reflected;
        if (settings.histogram) ++result.exit_counts[settings.binning.bin_of(d)];
        break;
      }
      if (depth > kThickness || std::isnan(depth)) {  // NaN: infinite flight with d.z = 0
        ++result.transmitted;
        break;
      }
      if (order == settings.max_order) {
        ++result.truncated;
        break;
      }
      const double u1 = rng.uniform(), u2 = rng.uniform();
      // The phase function takes the direction towards the previous vertex (-d) and returns the
      // outgoing direction, which is the new propagation direction.
      d = flakes.sample_phase(-d, u1, u2);
      ++order;
      ++result.scattering_events;
      if (settings.classify_by_last_direction && order == settings.max_order) {
        // Published rules: the path ends here, wherever it is, and its new direction decides.
        ++result.truncated;
        if (d.z >= 0.0) {
          ++result.reflected;
          if (settings.histogram) ++result.exit_counts[settings.binning.bin_of(d)];
        } else {
          ++result.transmitted;
        }
        break;
      }
    }
  }
  return result;
}

}  // namespace clothbake::sheen

// Monte Carlo simulation of the volumetric sheen layer of Zeltner, Burley and Chiang 2022: a
// homogeneous slab of unit thickness and unit density filled with fibre-like SGGX microflakes
// standing along the normal (sheen_layer.cpp documents the transport). Light enters from the top
// along -wo; the layer neither absorbs (albedo 1) nor has anything below it, so every path leaves
// either through the top (reflected) or through the bottom (transmitted): R + T = 1.
//
// The fraction of paths that leave through the top estimates the directional albedo R(wo) of the
// layer, and the histogram of their exit directions estimates f(wi, wo) cos(theta_i) / R, the
// normalised shape that the LTC lobe approximates (the layer is reciprocal, so the exit direction
// plays the role of wi).
#pragma once

#include <cstdint>
#include <vector>

#include "model/sheen.hpp"  // SheenConvention
#include "sheen/sggx_fibre.hpp"

namespace clothbake::sheen {

// The simulation rules of a table convention (docs/sheen.md, "Two conventions").
//   Published (Zeltner et al.'s fitting code, github.com/tizian/ltc-sheen, fitting/python/
//   precompute_brdf_values_sheen_volume.py and fitting/src/bsdfs/sheen_volume.h): a path is cut
//   right after its 16th scattering event and counts as reflected iff that last direction points
//   up (z >= 0), wherever the path is; cos theta_o and roughness are simulated at >= 0.01.
//   Converged: every path is followed until it leaves the slab (a cap of 1e5 events is never
//   reached; paths cut there are reported as truncated, never counted as reflected);
//   cos theta_o = 0 is simulated at 0.001, roughness 0 exactly (R = 0).
struct SheenSimulationRules {
  int max_order = 100000;                   // scattering events followed at most
  bool classify_by_last_direction = false;  // cut paths: reflected iff the last direction is up
  double min_cos = 1e-3;                    // cos theta_o is simulated at max(cos theta_o, min_cos)
  double min_roughness = 0.0;  // roughness is simulated at max(roughness, min_roughness)
};

// The rules of a convention; throws std::invalid_argument for a value outside the enum.
SheenSimulationRules simulation_rules(model::SheenConvention convention);

// Bins of exit directions over the upper hemisphere in the frame of wo (wo in the xz plane, x > 0),
// folded across the plane of incidence (the layer is symmetric in y): phi = atan2(|y|, x) in
// [0, pi] in phi_bins equal bins, and z = cos(theta) in z_bins bins with edges (k / z_bins)^2,
// which resolve the grazing directions where sheen concentrates. Bin (iz, iphi) has index
// iz * phi_bins + iphi and covers solid angle (z_hi - z_lo) * pi / phi_bins on each side.
struct ExitBinning {
  int z_bins = 32;
  int phi_bins = 32;

  int bin_count() const { return z_bins * phi_bins; }
  double z_edge(int k) const {
    const double t = double(k) / z_bins;
    return t * t;
  }
  // The bin of a unit direction with z > 0.
  int bin_of(const Vec3d& w) const;
};

struct LayerSimulation {
  uint64_t paths = 0;
  uint64_t reflected = 0;    // left through the top
  uint64_t transmitted = 0;  // left through the bottom
  // Cut at the allowed order. Converged rules: counted in neither reflected nor transmitted;
  // published rules (classify_by_last_direction): also counted in one of them by the direction of
  // their last scattering event, so that reflected + transmitted = paths.
  uint64_t truncated = 0;
  uint64_t scattering_events = 0;
  std::vector<uint64_t> exit_counts;  // reflected paths per ExitBinning bin

  double albedo() const { return paths ? double(reflected) / double(paths) : 0.0; }
  // Binomial standard error of albedo().
  double albedo_standard_error() const;
};

struct LayerSimulationSettings {
  uint64_t paths = 100000;
  uint64_t seed = 1;
  uint64_t stream = 0;  // independent random stream (e.g. the table entry index)
  // Highest scattering order followed; longer paths are counted as truncated. The default is far
  // beyond what an optical thickness of at most ~1 / cos(theta) needs (the report counts them).
  int max_order = 100000;
  // Published rules: a path ends right after scattering event max_order and counts as reflected
  // iff its new direction has z >= 0 (it is histogrammed by that direction).
  bool classify_by_last_direction = false;
  ExitBinning binning;
  bool histogram = true;  // fill exit_counts
};

// Simulates the sheen layer of the given roughness in [0, 1] for light arriving from the direction
// with cosine cos_theta_o in (0, 1] to the normal. Deterministic for the same settings.
// Throws std::invalid_argument for values outside those ranges.
LayerSimulation simulate_sheen_layer(double cos_theta_o, double roughness,
                                     const LayerSimulationSettings& settings);

// settings with the order cap and classification of `rules` (the clamps of cos theta_o and
// roughness are the caller's: see SheenSimulationRules::min_cos, min_roughness).
LayerSimulationSettings with_rules(LayerSimulationSettings settings,
                                   const SheenSimulationRules& rules);

}  // namespace clothbake::sheen

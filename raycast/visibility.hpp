// Per-texel visibility V(x, w) of the periodic height field and its ASG fit (paper Sec. 3.1, 4.2;
// docs/raycast.md, "Visibility").
//
// V(x, w) = 1 when a ray from the texel's surface point towards light direction w escapes above the
// highest point of the height field without hitting it. The surface point is the mesh vertex at the
// texel centre, (u, v, height), moved along the height field's geometric normal (central
// differences) by `normal_offset_texels` texel sizes, so the ray does not hit the triangles it
// starts on through rounding. Directions are the bin centres of DirectionGrid{dirs, 0} (equal solid
// angle over the hemisphere z > 0 of the macro surface).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "fabric/fabric.hpp"
#include "model/asg.hpp"
#include "raycast/asg_fit.hpp"
#include "raycast/heightfield_scene.hpp"

namespace clothbake::raycast {

// Largest sample set (one bit per texel and direction; 8 MiB at 256^2 x 32^2) a bake may hold.
inline constexpr double kMaxVisibilitySampleBytes = 2.0 * 1024 * 1024 * 1024;

struct VisibilitySettings {
  int dirs = 32;                       // n: n x n light directions, [1, 256]
  double normal_offset_texels = 0.01;  // ray origin offset along the normal, in texel sizes, > 0
  int rings = -1;                      // neighbour tiles replicated each side; -1: automatic
  // Warn about texels whose ASG fit RMS error exceeds this. The example weaves reach 0.33 to 0.35
  // at their 90th percentile (one lobe cannot follow a binary horizon; docs/raycast.md), so only
  // texels beyond what a single lobe normally gets are reported.
  double fit_warn_rms = 0.4;
  // How far sideways a ray is followed, tile widths, > 0 (raycast/heightfield_scene.hpp): a ray
  // that gets this far unblocked counts as visible and in VisibilitySamples::unresolved_rays.
  double max_sideways_tiles = kMaxSidewaysTiles;
};

// Binary samples, one bit per (texel, direction): bit (dir % 64) of word texel * words + dir / 64.
struct VisibilitySamples {
  int resolution = 0;
  int dirs = 0;
  int words_per_texel = 0;
  std::vector<uint64_t> bits;
  uint64_t rays = 0, segments = 0;
  uint64_t unresolved_rays = 0;     // cut by the sideways budget unblocked: counted as visible
  double max_sideways_tiles = 0.0;  // that budget (raycast/heightfield_scene.hpp)
  int rings = 0;

  bool visible(std::size_t texel, int dir) const {
    return (bits[texel * std::size_t(words_per_texel) + std::size_t(dir / 64)] >> (dir % 64)) & 1u;
  }
  // Fraction of the sampled hemisphere that texel sees.
  double visible_fraction(std::size_t texel) const;
};

struct VisibilityAsgs {
  int resolution = 0;
  std::vector<model::AsgRecord> records;  // y * N + x: the packed lobe
  std::vector<float> fit_error;           // RMS over the samples of the packed lobe, in [0, 2]
  // Statistics.
  double mean_fit_error = 0.0, max_fit_error = 0.0;
  std::size_t worst_texel = 0;
  std::size_t texels_above_warning = 0;
  std::size_t distinct_patterns = 0;  // distinct sample patterns: the fits actually run
  uint64_t fit_evaluations = 0;       // objective evaluations of those fits
};

void validate_visibility_settings(const VisibilitySettings& settings);

// Casts N^2 x dirs^2 occlusion rays (16-wide packets of 4 x 4 texels sharing one direction, TBB
// over texel tiles; result independent of the thread count). Throws Error(Input) for bad settings,
// more samples than kMaxVisibilitySampleBytes (naming the keys) or a non-finite height (naming the
// texel). A flat map sees the whole sky (every bit set) without casting rays.
// `progress` (optional) is called from worker threads with the fraction of the work done.
VisibilitySamples sample_visibility(const FabricMaps& maps, const VisibilitySettings& settings,
                                    const std::function<void(double)>& progress = {});

// The sample directions of the visibility, as the ASG fit takes them: the bin centres of
// DirectionGrid{dirs, 0} in bin order (bin_index(i, j) = j * dirs + i), the order of the sample
// bits.
FitDirections visibility_fit_directions(int dirs);

// Fits one ASG per texel (raycast/asg_fit.hpp), packs it, and records the RMS error of the
// packed lobe. Texels with identical samples share one fit (run once per distinct pattern; the
// same records as fitting each texel). Warns once, naming the count and the worst texel (the
// first in texel order), when texels exceed settings.fit_warn_rms.
VisibilityAsgs fit_visibility(const VisibilitySamples& samples, const VisibilitySettings& settings,
                              const std::function<void(double)>& progress = {});

}  // namespace clothbake::raycast

// Parallax tables (paper Sec. 3.2, Eq. 2) and their per-direction summed-area tables for the
// parallax transition (Sec. 5.2).
//
// Definition (docs/raycast.md, "Parallax"): the reference plane is z_ref = the largest height of
// the tile. For texel t (centre u_t) and view direction o (unit, pointing from the surface towards
// the viewer, o.z >= min_cos), a ray enters at (u_t, z_ref) and travels along -o; its first hit
// with the periodic height field is at height z_hit. The table stores
//
//     r(t, o) = z_hit - z_ref   (tile-side units, r <= 0)
//
// so that Eq. 2 holds as printed: u_new = u_t + (r / o.z) (o.x, o.y) is the texel-space position of
// the first visible point (r / o.z <= 0 times o: a step away from the viewer). On disk the depth
// -r is a 16-bit code: r = -code * depth_scale, depth_scale = (z_max - z_min) / 65535, so the
// quantisation error is at most depth_scale / 2 = range / 131070 (exact integers make SAT queries
// exact; docs/raycast.md explains the choice over fp16).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "fabric/fabric.hpp"

namespace clothbake::raycast {

// Largest parallax table plus SAT a bake may build (6 bytes per texel and direction; 384 MiB at
// 256^2 x 32^2): beyond, bake_parallax refuses with an input error instead of exhausting memory.
inline constexpr double kMaxParallaxBytes = 8.0 * 1024 * 1024 * 1024;

struct ParallaxSettings {
  int dirs = 32;         // n: n x n view directions on DirectionGrid{n, min_cos}, [1, 256]
  double min_cos = 0.6;  // the cap: view directions with cos(theta) >= min_cos, [0, 1)
  int rings = -1;        // neighbour tiles replicated each side; -1: chosen from the heights
  // Empty, or one entry per direction bin: directions with keep[d] == 0 cast no rays and keep
  // code 0 (a scene-planned bake, which stores only the kept ones).
  std::vector<uint8_t> keep;
};

struct ParallaxStats {
  uint64_t rays = 0;             // rays cast
  uint64_t segments = 0;         // Embree casts (> rays when rays crossed the neighbourhood)
  uint64_t recast_rays = 0;      // rays that slipped through an edge and were cast again
  uint64_t unresolved_rays = 0;  // rays that never hit (given the bottom depth); warned about
  int rings = 0;                 // neighbour tiles replicated each side
  double max_sideways = 0.0;     // largest |offset| = depth tan(theta) over the table, tiles
  double max_quantization_error = 0.0;  // max |r - decoded r| over the table, tile-side units
};

struct ParallaxTable {
  int resolution = 0;  // N
  int dirs = 0;        // n (n^2 directions)
  double min_cos = 0.6;
  double reference_height = 0.0;  // z_ref = max height, tile-side units
  double depth_scale = 0.0;       // tile-side units per code (0 for a flat map)
  // depth codes [dir][texel]: dir = DirectionGrid::bin_index(i, j), texel = y * N + x.
  std::vector<uint16_t> depth;
  ParallaxStats stats;

  std::size_t texel_count() const { return std::size_t(resolution) * std::size_t(resolution); }
  // r of bin `dir` at texel (x, y), decoded (<= 0). Precondition: indices in range.
  double r(int dir, int x, int y) const {
    return -double(depth[std::size_t(dir) * texel_count() + std::size_t(y) * resolution + x]) *
           depth_scale;
  }
};

// Validates the settings; throws Error(Input) naming the key ("bake.parallax_dirs",
// "bake.parallax_min_cos").
void validate_parallax_settings(const ParallaxSettings& settings);

// Called with the fraction of the work done, from worker threads (must be thread-safe and cheap).
using ProgressCallback = std::function<void(double)>;

// Casts resolution^2 x dirs^2 rays (4 x 4 blocks of neighbouring texels sharing one direction,
// cast as one 16-wide packet, docs/raycast.md; TBB over texel blocks; the result does not depend
// on the thread count).
// Throws Error(Input) for bad settings, a table larger than kMaxParallaxBytes (naming the keys) or
// a non-finite height (naming the texel). Warns (common/
// diagnostics) when rays never hit (Embree edge leaks that survived a re-cast) and when the heights
// are so tall that offsets exceed a tile. A flat map gives r = 0 without casting rays.
ParallaxTable bake_parallax(const FabricMaps& maps, const ParallaxSettings& settings,
                            const ProgressCallback& progress = {});

// Per-direction summed-area tables of the depth codes: sat[dir][y * N + x] = sum of codes over
// texels [0, x] x [0, y], modulo 2^32 (unsigned wrap-around). Rectangle sums taken with the same
// modular arithmetic are exact whenever the true sum is below 2^32, i.e. for any rectangle of at
// most 65537 texels (ParallaxView::footprint_depth in formats/reader/parallax_sections.hpp sums
// larger ones in bands).
std::vector<uint32_t> parallax_sat(const ParallaxTable& table);
// The same from raw codes [dir][texel] (dir_count * resolution^2 values) into `out` (as many).
void parallax_sat(const uint16_t* codes, int resolution, int dir_count, uint32_t* out);

}  // namespace clothbake::raycast

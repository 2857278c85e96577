// What every parallax compressor shares (the one compressed form is the hierarchical table of
// compress/parallax_hierarchy.hpp; docs/compression.md, "Hierarchical parallax"): the raw table as
// the parallax stage produces it, the input check and the offset per unit depth of each view
// direction.
//
// Deterministic. C++20. Errors: clothbake::Error(Input) for an empty table or an error target out
// of range.
#pragma once

#include <cstdint>
#include <vector>

namespace clothbake::compress {

// Default [bake] parallax_max_error: RMS Eq. 2 offset error in texels over every texel and bin
// centre, the target of the hierarchical table's per-direction steps (docs/compression.md).
inline constexpr double kDefaultParallaxMaxError = 0.05;

// The raw table as the parallax stage produces it (raycast::ParallaxTable without the dependency).
struct ParallaxCodes {
  const uint16_t* codes = nullptr;  // [dir][y][x], dir = j * n + i
  int resolution = 0;               // N
  int dirs = 0;                     // n
  double min_cos = 0.6;
  double depth_scale = 0.0;  // r = -code * depth_scale
  double reference_height = 0.0;
  double max_offset = 0.0;  // tile units (information)
};

// N tan(theta_d) at the bin centres: texels of Eq. 2 offset per unit of depth, D values.
std::vector<double> parallax_offset_per_depth(int resolution, int dirs, double min_cos);

// Throws Error(Input) for an empty table or max_error outside (0, 1] (naming
// bake.parallax_max_error): the check of every parallax compressor.
void check_parallax_compression_input(const ParallaxCodes& raw, double max_error);

}  // namespace clothbake::compress

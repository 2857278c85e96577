// Random footprints for verification, by size class: from one texel to several tiles, anywhere on
// the infinite periodic plane (negative coordinates included), with real-valued or texel-aligned
// corners and aspect ratios up to 2:1. Deterministic (SplitMix64 from a seed).
//
// Size classes by the footprint's side s = sqrt(width * height), in texels, for a tile of N:
//   "1"  [1, 2)   "2"  [2, 4)   "4"  [4, 16)   "16" [16, 64)   "64" [64, N)
//   "tile" [N, 2N)   "tiles" [2N, 5N]
// (classes that would be empty for a small N are dropped). C++20.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "formats/reader/radiance_query.hpp"

namespace clothbake::verify {

struct SizeClass {
  std::string name;
  double min_side = 0, max_side = 0;  // [min, max) in texels
};

// The size classes of a tile of side n (non-empty ones only).
std::vector<SizeClass> size_classes(int n);

struct SampledFootprint {
  reader::Footprint rect;
  int size_class = 0;       // index into size_classes(n)
  double h[3] = {0, 0, 1};  // a random unit half vector (upper hemisphere)
};

// `count` footprints spread evenly over the classes (round robin), each with a random half
// vector; the first footprint of the first class is the one-texel footprint at the far corner of
// the tile, [N-1, N) x [N-1, N).
std::vector<SampledFootprint> sample_footprints(int n, int count, uint64_t seed);

// Texel coverage of [a0, a1) on a periodic axis of n texels: covered length per texel column.
std::vector<double> axis_coverage(double a0, double a1, int n);

}  // namespace clothbake::verify

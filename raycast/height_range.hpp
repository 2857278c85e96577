// The finite height range of a fabric's height map, shared by the parallax and visibility stages
// (both place ray origins and end rays relative to it).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"
#include "fabric/fabric.hpp"

namespace clothbake::raycast {

struct HeightRange {
  double min = 0.0;
  double max = 0.0;
};

// Lowest and highest height of a validated map (height.size() == texel_count()), in tile-side
// units. Throws Error(Input) naming the first non-finite texel. Safe on any map content.
inline HeightRange height_range(const FabricMaps& maps) {
  HeightRange r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (int y = 0; y < maps.resolution; ++y)
    for (int x = 0; x < maps.resolution; ++x) {
      const float h = maps.height[maps.index(x, y)];
      if (!std::isfinite(h))
        throw_input_error("height map: texel (" + std::to_string(x) + ", " + std::to_string(y) +
                          ") is not a finite number");
      r.min = std::min(r.min, double(h));
      r.max = std::max(r.max, double(h));
    }
  return r;
}

}  // namespace clothbake::raycast

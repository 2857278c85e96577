// Shading normals derived from a height field, for fabrics whose description gives no normal map.
#pragma once

#include <vector>

#include "fabric/fabric.hpp"

namespace clothbake::inputs {

// n = normalize(-dh/du, -dh/dv, 1) at every texel of an N x N periodic height field in tile-side
// units (u, v in [0, 1) over the tile, so the texel spacing is 1/N), with the gradient taken by
// central differences that wrap around the tile edges: dh/du ~ (h[x+1] - h[x-1]) * N / 2.
// Preconditions: resolution >= 1 and height.size() == resolution^2, finite heights (the loader
// has checked them). Never fails; z is always > 0.
std::vector<Vec3f> normals_from_height(const std::vector<float>& height, int resolution);

}  // namespace clothbake::inputs

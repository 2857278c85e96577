// A ray-traced reference of a cloth plane's real relief (paper Fig. 6, docs/rendering.md "Near
// field"): the camera rays hit the displaced height field itself (the asset's height map as the
// Embree mesh the parallax stage traces, raycast/heightfield_scene.hpp), each hit is shaded with
// the BSDF of the texel it lands on, and the light is tested with a shadow ray against the relief
// (no ASG, no parallax table). Pixels are integrated with s x s stratified sub-pixel rays.
//
// The macro plane is the top of the relief (the parallax tables' reference plane z_max): a
// camera ray enters the tile where it crosses the object's plane and travels down into the relief.
// Pixels that do not see the object are 0 and left out of comparisons (mask).
//
// C++20; throws clothbake::Error(Input) when the object is not a plane with an asset.
#pragma once

#include <vector>

#include "render/renderer.hpp"

namespace clothbake::render {

struct HeightfieldReference {
  RenderResult image;
  std::vector<uint8_t> mask;  // 1 where the pixel's centre ray hits the object
};

HeightfieldReference render_heightfield_reference(const Scene& scene, std::size_t object,
                                                  uint32_t samples_per_side);

}  // namespace clothbake::render

// Limits every loaded or generated feature map must satisfy before any stage traces it
// (docs/fabric-format.md, "Height limits"): finite values everywhere, and heights bounded relative
// to the tile, so that ray casting (Embree) and the parallax march stay within what they can
// resolve. Reliefs beyond the bound are refused at load with the map (or weave keys) and pixel.
#pragma once

#include <string>

#include "fabric/fabric.hpp"

namespace clothbake::inputs {

// Largest |height| accepted, in tile-side units (a relief 64 tiles tall; woven reliefs are below
// 1). Beyond this the parallax march and Embree's ray-box tests lose all precision.
inline constexpr double kMaxHeightTiles = 64.0;

// Throws Error(Input) "WHERE: height at pixel (x, y) = V ... HINT" for the first height that is
// not finite or |height| > kMaxHeightTiles; `hint` names the keys that produced it (e.g.
// "[maps] height_scale" or "[weave.warp] spacing_mm and height_mm").
void check_heights(const std::vector<float>& height, int resolution, const std::string& where,
                   const std::string& hint);

// Throws Error(Input) for the first non-finite value of any map (height, tangent, normal, gap,
// albedo), naming the map, the pixel and `hint`.
void check_maps_finite(const FabricMaps& maps, const std::string& where, const std::string& hint);

}  // namespace clothbake::inputs

// Feature map limits (map_limits.hpp).
#include "bake/inputs/map_limits.hpp"

#include <fmt/format.h>

#include <cmath>

#include "common/error.hpp"

namespace clothbake::inputs {

void check_heights(const std::vector<float>& height, int resolution, const std::string& where,
                   const std::string& hint) {
  for (std::size_t i = 0; i < height.size(); ++i) {
    const double h = height[i];
    if (std::isfinite(h) && std::fabs(h) <= kMaxHeightTiles) continue;
    const std::size_t n = std::size_t(resolution > 0 ? resolution : 1);
    throw_input_error(fmt::format(
        "{}: height at pixel ({}, {}) is {} tile widths; heights must be finite and within "
        "+-{} tile widths (a relief that tall cannot be ray traced){}",
        where, i % n, i / n, h, kMaxHeightTiles, hint.empty() ? "" : "; check " + hint));
  }
}

void check_maps_finite(const FabricMaps& maps, const std::string& where, const std::string& hint) {
  const std::size_t n = std::size_t(maps.resolution > 0 ? maps.resolution : 1);
  auto fail = [&](const char* map, std::size_t i) {
    throw_input_error(fmt::format("{}: the {} map is not finite at pixel ({}, {}){}", where, map,
                                  i % n, i / n, hint.empty() ? "" : "; check " + hint));
  };
  auto finite3 = [](const Vec3f& v) {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
  };
  for (std::size_t i = 0; i < maps.height.size(); ++i)
    if (!std::isfinite(maps.height[i])) fail("height", i);
  for (std::size_t i = 0; i < maps.tangent.size(); ++i)
    if (!finite3(maps.tangent[i])) fail("tangent", i);
  for (std::size_t i = 0; i < maps.normal.size(); ++i)
    if (!finite3(maps.normal[i])) fail("normal", i);
  for (std::size_t i = 0; i < maps.gap.size(); ++i)
    if (!std::isfinite(maps.gap[i])) fail("gap", i);
  for (std::size_t i = 0; i < maps.albedo.size(); ++i)
    if (!finite3(maps.albedo[i])) fail("albedo", i);
}

}  // namespace clothbake::inputs

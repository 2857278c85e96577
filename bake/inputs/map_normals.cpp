#include "bake/inputs/map_normals.hpp"

#include <cmath>

namespace clothbake::inputs {

std::vector<Vec3f> normals_from_height(const std::vector<float>& height, int resolution) {
  const int n = resolution;
  std::vector<Vec3f> out(std::size_t(n) * n);
  auto h = [&](int x, int y) {
    x = (x % n + n) % n;
    y = (y % n + n) % n;
    return double(height[std::size_t(y) * n + x]);
  };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double du = (h(x + 1, y) - h(x - 1, y)) * n * 0.5;
      double dv = (h(x, y + 1) - h(x, y - 1)) * n * 0.5;
      double len = std::sqrt(du * du + dv * dv + 1.0);
      out[std::size_t(y) * n + x] = Vec3f{float(-du / len), float(-dv / len), float(1.0 / len)};
    }
  return out;
}

}  // namespace clothbake::inputs

// An environment light from an equirectangular map (scene.hpp, EnvironmentMap): radiance look-up
// and importance sampling proportional to luminance times solid angle, for the light-sampling
// half of multiple importance sampling (docs/rendering.md, "Lights").
//
// Each pixel is a constant-radiance patch [phi0, phi1) x [theta0, theta1); a sample picks a pixel
// with probability w = lum * solid angle / sum, then a direction uniform in the patch's solid
// angle (uniform phi, uniform cos theta), so pdf(direction) = w / solid angle of its pixel.
// C++20; construction allocates two tables; queries do not allocate.
#pragma once

#include <vector>

#include "render/scene.hpp"

namespace clothbake::render {

class Environment {
 public:
  explicit Environment(const EnvironmentMap& map);

  // Radiance arriving from world direction `d` (unit), times the map's scale.
  Rgb radiance(const Vec3& d) const;
  // A direction drawn with density pdf() from two uniform numbers in [0, 1).
  Vec3 sample(double u1, double u2, double* pdf) const;
  // Solid-angle density of sample() at `d` (unit); 0 on black pixels.
  double pdf(const Vec3& d) const;

 private:
  int pixel_of(const Vec3& d) const;  // y * W + x
  const EnvironmentMap* map_;
  std::vector<double> row_cdf_;     // H + 1 entries
  std::vector<double> column_cdf_;  // H x (W + 1) entries, per row
  std::vector<double> weight_;      // per pixel, normalised (sums to 1)
};

}  // namespace clothbake::render

// Pinhole camera rays and pixel footprints (camera.hpp).
#include "render/camera.hpp"

#include <cmath>

namespace clothbake::render {

PinholeCamera::PinholeCamera(const Camera& c) : width_(c.width), height_(c.height) {
  origin_ = c.position;
  forward_ = normalize(c.look_at - c.position);
  const Vec3 right = normalize(cross(forward_, c.up));
  const Vec3 up = cross(right, forward_);
  const double half_h = std::tan(0.5 * c.fov_deg * 3.14159265358979323846 / 180.0);
  const double half_w = half_h * double(c.width) / double(c.height);
  right_ = right * half_w;
  up_ = up * half_h;
}

CameraRay PinholeCamera::generate(double x, double y) const {
  // Image-plane point at distance 1: forward + a right + b up, a, b in [-1, 1].
  const double a = 2.0 * x / width_ - 1.0, b = 1.0 - 2.0 * y / height_;
  const Vec3 d = forward_ + right_ * a + up_ * b;
  const Vec3 dd_dx = right_ * (2.0 / width_), dd_dy = up_ * (-2.0 / height_);
  const double len2 = dot(d, d), len = std::sqrt(len2);
  // d(D/|D|) = (dD |D|^2 - D (D.dD)) / |D|^3
  auto unit_derivative = [&](const Vec3& dD) {
    return (dD * len2 - d * dot(d, dD)) / (len2 * len);
  };
  CameraRay r;
  r.ray = {origin_, d / len};
  r.ddx = unit_derivative(dd_dx);
  r.ddy = unit_derivative(dd_dy);
  return r;
}

SurfaceDifferentials surface_differentials(const CameraRay& ray, const SurfaceHit& hit) {
  return model::uv_differentials(hit.t, ray.ray.direction, ray.ddx, ray.ddy, hit.normal, hit.dpdu,
                                 hit.dpdv);
}

reader::Footprint footprint_rectangle(double u, double v, const SurfaceDifferentials& d,
                                      double texels_per_unit) {
  constexpr double kMaxSide = 1073741824.0;  // 2^30 texels
  const model::FootprintRectangle r = model::pixel_footprint(u, v, d, texels_per_unit, kMaxSide);
  return {r.u0, r.v0, r.u1, r.v1};
}

}  // namespace clothbake::render

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
  SurfaceDifferentials out;
  const Vec3& n = hit.normal;
  const double dn = dot(ray.ray.direction, n);
  if (!(std::abs(dn) > 1e-12)) return out;  // grazing: no finite footprint
  // Transfer to the tangent plane: dP = t dD - ((t dD).n / (D.n)) D   (origin fixed).
  auto transfer = [&](const Vec3& dd) {
    const Vec3 m = dd * hit.t;
    return m - ray.ray.direction * (dot(m, n) / dn);
  };
  const Vec3 px = transfer(ray.ddx), py = transfer(ray.ddy);
  // Least squares dP = du dpdu + dv dpdv: the 2 x 2 Gram system.
  const double a = dot(hit.dpdu, hit.dpdu), b = dot(hit.dpdu, hit.dpdv),
               c = dot(hit.dpdv, hit.dpdv);
  const double det = a * c - b * b;
  if (!(std::abs(det) > 1e-300)) return out;
  auto solve = [&](const Vec3& dp, double& du, double& dv) {
    const double ru = dot(dp, hit.dpdu), rv = dot(dp, hit.dpdv);
    du = (c * ru - b * rv) / det;
    dv = (a * rv - b * ru) / det;
  };
  solve(px, out.du_dx, out.dv_dx);
  solve(py, out.du_dy, out.dv_dy);
  return out;
}

reader::Footprint footprint_rectangle(double u, double v, const SurfaceDifferentials& d,
                                      double texels_per_unit) {
  constexpr double kMaxSide = 1073741824.0;  // 2^30 texels
  const double s = texels_per_unit;
  double w = (std::abs(d.du_dx) + std::abs(d.du_dy)) * s;
  double h = (std::abs(d.dv_dx) + std::abs(d.dv_dy)) * s;
  const double area = std::abs(d.du_dx * d.dv_dy - d.du_dy * d.dv_dx) * s * s;
  if (w > 0 && h > 0 && area > 0 && area < w * h) {
    const double shrink = std::sqrt(area / (w * h));
    w *= shrink;
    h *= shrink;
  }
  if (!(w <= kMaxSide)) w = kMaxSide;  // NaN too
  if (!(h <= kMaxSide)) h = kMaxSide;
  return {u - 0.5 * w, v - 0.5 * h, u + 0.5 * w, v + 0.5 * h};
}

}  // namespace clothbake::render

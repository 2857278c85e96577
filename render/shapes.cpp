// Ray intersection of planes, open cylinders and spheres (shapes.hpp).
#include "render/shapes.hpp"

#include <algorithm>
#include <cmath>

#include "model/directions.hpp"

namespace clothbake::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Azimuth of `r` (perpendicular to the axis) in [0, 2 pi).
double azimuth(const Vec3& r, const Vec3& e1, const Vec3& e2) {
  double phi = std::atan2(dot(r, e2), dot(r, e1));
  return phi < 0 ? phi + 2 * kPi : phi;
}

SurfaceHit plane_hit(const Ray& ray, const Object& o, double t_min, double t_max) {
  SurfaceHit h;
  const Vec3 n = normalize(o.normal);
  const double denom = dot(ray.direction, n);
  if (!(std::abs(denom) > 1e-300)) return h;
  const double t = dot(o.center - ray.origin, n) / denom;
  if (!(t > t_min && t < t_max)) return h;
  const Vec3 p = ray.origin + ray.direction * t;
  const Vec3 tu = normalize(o.tangent - n * dot(o.tangent, n));
  const Vec3 tv = cross(n, tu);
  const double a = dot(p - o.center, tu), b = dot(p - o.center, tv);
  if (!(std::abs(a) <= 0.5 * o.size[0] && std::abs(b) <= 0.5 * o.size[1])) return h;
  h.t = t;
  h.point = p;
  h.normal = n;
  h.dpdu = tu;
  h.dpdv = tv;
  h.u = a + 0.5 * o.size[0];
  h.v = b + 0.5 * o.size[1];
  return h;
}

SurfaceHit cylinder_hit(const Ray& ray, const Object& o, double t_min, double t_max) {
  SurfaceHit best;
  const Vec3 a = normalize(o.axis);
  Vec3 e1, e2;
  axis_frame(a, e1, e2);
  // |(o + t d - c) - ((o + t d - c).a) a|^2 = R^2 in the plane perpendicular to the axis.
  const Vec3 oc = ray.origin - o.center;
  const Vec3 dp = ray.direction - a * dot(ray.direction, a);
  const Vec3 op = oc - a * dot(oc, a);
  const double qa = dot(dp, dp), qb = 2 * dot(dp, op), qc = dot(op, op) - o.radius * o.radius;
  if (!(qa > 1e-300)) return best;  // parallel to the axis
  const double disc = qb * qb - 4 * qa * qc;
  if (!(disc >= 0)) return best;
  const double sq = std::sqrt(disc);
  const double q = qb < 0 ? -0.5 * (qb - sq) : -0.5 * (qb + sq);  // no cancellation
  double roots[2] = {q / qa, qc / q};
  if (roots[0] > roots[1]) std::swap(roots[0], roots[1]);
  for (double t : roots) {
    if (!(t > t_min && t < t_max) || !std::isfinite(t)) continue;
    const Vec3 p = ray.origin + ray.direction * t;
    const double along = dot(p - o.center, a);
    if (!(std::abs(along) <= 0.5 * o.height)) continue;
    const Vec3 r = p - o.center - a * along;
    const double phi = azimuth(r, e1, e2);
    best.t = t;
    best.point = p;
    best.normal = normalize(r);
    best.dpdu = e2 * std::cos(phi) - e1 * std::sin(phi);  // d/du = (1/R) d/dphi: unit
    best.dpdv = a;
    best.u = o.radius * phi;
    best.v = along + 0.5 * o.height;
    return best;
  }
  return best;
}

SurfaceHit sphere_hit(const Ray& ray, const Object& o, double t_min, double t_max) {
  SurfaceHit best;
  const Vec3 oc = ray.origin - o.center;
  const double qb = dot(oc, ray.direction), qc = dot(oc, oc) - o.radius * o.radius;
  const double disc = qb * qb - qc;
  if (!(disc >= 0)) return best;
  const double sq = std::sqrt(disc);
  const double q = qb < 0 ? -qb + sq : -qb - sq;  // -(b + sign(b) sqrt): no cancellation
  double roots[2] = {q, q != 0 ? qc / q : q};
  if (roots[0] > roots[1]) std::swap(roots[0], roots[1]);
  const Vec3 a = normalize(o.axis);
  Vec3 e1, e2;
  axis_frame(a, e1, e2);
  for (double t : roots) {
    if (!(t > t_min && t < t_max) || !std::isfinite(t)) continue;
    const Vec3 p = ray.origin + ray.direction * t;
    const Vec3 n = normalize(p - o.center);
    const double cos_theta = std::clamp(dot(n, a), -1.0, 1.0);
    const double theta = std::acos(cos_theta), sin_theta = std::sin(theta);
    const Vec3 r = n - a * cos_theta;
    const double phi = azimuth(r, e1, e2);
    const Vec3 around = e2 * std::cos(phi) - e1 * std::sin(phi);
    best.t = t;
    best.point = p;
    best.normal = n;
    best.dpdu = around * sin_theta;  // u = R phi: |dP/du| = sin(theta)
    best.dpdv = a * (-sin_theta) + (e1 * std::cos(phi) + e2 * std::sin(phi)) * cos_theta;
    best.u = o.radius * phi;
    best.v = o.radius * theta;
    return best;
  }
  return best;
}

}  // namespace

void axis_frame(const Vec3& axis, Vec3& e1, Vec3& e2) {
  model::orthonormal_basis(axis, e1, e2);
}

SurfaceHit intersect(const Ray& ray, const Object& object, double t_min, double t_max) {
  switch (object.shape) {
    case ShapeType::Plane:
      return plane_hit(ray, object, t_min, t_max);
    case ShapeType::Cylinder:
      return cylinder_hit(ray, object, t_min, t_max);
    case ShapeType::Sphere:
      return sphere_hit(ray, object, t_min, t_max);
  }
  return {};
}

SurfaceHit intersect_scene(const Ray& ray, const std::vector<Object>& objects, double t_min,
                           double t_max) {
  SurfaceHit best;
  for (std::size_t k = 0; k < objects.size(); ++k) {
    SurfaceHit h = intersect(ray, objects[k], t_min, best.hit() ? best.t : t_max);
    if (h.t < best.t) {
      best = h;
      best.object = int(k);
    }
  }
  return best;
}

bool occluded(const Ray& ray, const std::vector<Object>& objects, double t_min, double t_max) {
  for (const Object& o : objects)
    if (std::isfinite(intersect(ray, o, t_min, t_max).t)) return true;
  return false;
}

bool inside(const Object& object, const Vec3& point) {
  const Vec3 d = point - object.center;
  if (object.shape == ShapeType::Sphere) return dot(d, d) < object.radius * object.radius;
  if (object.shape == ShapeType::Cylinder) {
    const Vec3 a = normalize(object.axis);
    const double along = dot(d, a);
    const Vec3 r = d - a * along;
    return std::abs(along) < 0.5 * object.height && dot(r, r) < object.radius * object.radius;
  }
  return false;
}

}  // namespace clothbake::render

// Reference ray casts for the tests, in double precision, written independently of Embree:
//  - first_hit_1d: exact for height fields that vary along x only (then both triangles of every
//    quad are coplanar and the mesh is the piecewise-linear interpolation P(x) of the texel-centre
//    heights, periodic), walking the linear pieces the ray crosses;
//  - first_hit_brute_force: every triangle of the mesh in a block of tiles, Moller-Trumbore.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "model/vec.hpp"

namespace clothbake::raycast::rctest {

using model::Vec3d;
constexpr double kNoHit = std::numeric_limits<double>::infinity();

inline long wrap(long i, long n) {
  long r = i % n;
  return r < 0 ? r + n : r;
}

// Heights of a 1-D profile: h[x], texel centres (x + 0.5) / n.
struct Profile {
  std::vector<double> h;
  double at(double x) const {  // P(x), periodic piecewise-linear
    const long n = long(h.size());
    double s = x * double(n) - 0.5;
    double i = std::floor(s);
    double f = s - i;
    return (1 - f) * h[wrap(long(i), n)] + f * h[wrap(long(i) + 1, n)];
  }
};

// First t in [0, t_max] where the ray o + t d is on or below P (the ray must start above it).
inline double first_hit_1d(const Profile& p, const Vec3d& o, const Vec3d& d, double t_max) {
  auto f = [&](double t) { return o.z + t * d.z - p.at(o.x + t * d.x); };
  if (f(0) <= 0) return 0;
  const double n = double(p.h.size());
  if (std::abs(d.x) < 1e-300) {  // P is constant along the ray
    if (d.z >= 0) return kNoHit;
    double t = -f(0) / d.z;
    return t <= t_max ? t : kNoHit;
  }
  // Breakpoints where x crosses a texel centre: x = (k + 0.5) / n.
  double t = 0;
  while (t < t_max) {
    double x = o.x + t * d.x;
    double s = x * n - 0.5;
    double next = d.x > 0 ? std::floor(s) + 1 : std::ceil(s) - 1;
    double t_next = std::min(((next + 0.5) / n - o.x) / d.x, t_max);
    if (t_next <= t) t_next = std::nextafter(t, kNoHit);
    double f0 = f(t), f1 = f(t_next);
    if (f1 <= 0) return t + (t_next - t) * f0 / (f0 - f1);  // f is linear on the piece
    t = t_next;
  }
  return kNoHit;
}

// Brute force over every triangle of the mesh of `heights` (n x n, float values as Embree sees
// them) in tiles [-tiles, tiles]^2 around the origin tile; vertices at float((v + 0.5) / n) + tile.
inline double first_hit_brute_force(const std::vector<float>& heights, int n, int tiles,
                                    const Vec3d& o, const Vec3d& d, double t_max) {
  auto vertex = [&](long vx, long vy, long tx, long ty) {
    return Vec3d{double(float((vx + 0.5) / n)) + tx, double(float((vy + 0.5) / n)) + ty,
                 double(heights[std::size_t(wrap(vy, n) * n + wrap(vx, n))])};
  };
  auto intersect = [&](const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    Vec3d e1 = b - a, e2 = c - a;
    Vec3d p = model::cross(d, e2);
    double det = model::dot(e1, p);
    if (std::abs(det) < 1e-300) return kNoHit;
    Vec3d s = o - a;
    double u = model::dot(s, p) / det;
    if (u < 0 || u > 1) return kNoHit;
    Vec3d q = model::cross(s, e1);
    double v = model::dot(d, q) / det;
    if (v < 0 || u + v > 1) return kNoHit;
    double t = model::dot(e2, q) / det;
    return t >= 0 && t <= t_max ? t : kNoHit;
  };
  double best = kNoHit;
  for (long ty = -tiles; ty <= tiles; ++ty)
    for (long tx = -tiles; tx <= tiles; ++tx)
      for (long qy = 0; qy < n; ++qy)
        for (long qx = 0; qx < n; ++qx) {
          Vec3d a = vertex(qx, qy, tx, ty), b = vertex(qx + 1, qy, tx, ty);
          Vec3d c = vertex(qx + 1, qy + 1, tx, ty), e = vertex(qx, qy + 1, tx, ty);
          best = std::min({best, intersect(a, b, c), intersect(a, c, e)});
        }
  return best;
}

}  // namespace clothbake::raycast::rctest

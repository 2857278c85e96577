// The shading frame of a surface hit (docs/rendering.md): z = the geometric normal, x along dP/du
// (the fabric's u texel axis), y = z x x. Shared by the renderer and the usage analysis, so that
// both see the same local directions.
#pragma once

#include "model/vec.hpp"
#include "render/shapes.hpp"

namespace clothbake::render {

struct ShadingFrame {
  Vec3 x, y, z;
  explicit ShadingFrame(const SurfaceHit& h) : z(h.normal) {
    x = normalize(h.dpdu - z * dot(z, h.dpdu));
    if (!(length(x) > 0.5)) {
      Vec3 s, t;
      model::orthonormal_basis(z, s, t);
      x = s;
    }
    y = cross(z, x);
  }
  Vec3 local(const Vec3& v) const { return {dot(v, x), dot(v, y), dot(v, z)}; }
  Vec3 world(const Vec3& v) const { return x * v.x + y * v.y + z * v.z; }
};

// The offset origin of a shadow ray leaving the hit towards wi (world), on wi's side of the
// surface: the renderer's and the usage analysis's shadow tests agree.
inline Vec3 shadow_ray_origin(const SurfaceHit& hit, const Vec3& wi) {
  const double eps =
      1e-7 * (1.0 + std::abs(hit.point.x) + std::abs(hit.point.y) + std::abs(hit.point.z) + hit.t);
  return hit.point + hit.normal * (dot(hit.normal, wi) > 0 ? eps : -eps);
}

}  // namespace clothbake::render

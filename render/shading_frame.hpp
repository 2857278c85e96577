// The shading frame of a surface hit (docs/rendering.md): z = the geometric normal, x along dP/du
// (the fabric's u texel axis), y = z x x. Shared by the renderer and the usage analysis, so that
// both see the same local directions.
#pragma once

#include <cmath>
#include <vector>

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

// What a point or directional light delivers at `hit` when nothing shadows it: the direction
// towards it (world, unit) and the irradiance on a surface facing it (a point light's intensity
// over the squared distance, a directional light's irradiance). False when the light is shadowed
// there (the shadow ray from shadow_ray_origin, up to the light), when a point light sits on the
// hit, and for environment lights (sampled by their own rules). The one shadow test of these lights
// for the renderer, its interior-pixel mask and the usage analysis.
struct LightArrival {
  Vec3 wi;
  Rgb irradiance;
};
inline bool unshadowed_light(const Light& light, const SurfaceHit& hit,
                             const std::vector<Object>& objects, LightArrival* out) {
  if (light.type == LightType::Point) {
    const Vec3 to = light.position - hit.point;
    const double dist = length(to);
    if (!(dist > 0)) return false;
    out->wi = to / dist;
    out->irradiance = light.intensity / (dist * dist);
    return !occluded({shadow_ray_origin(hit, out->wi), out->wi}, objects, 0.0, dist * (1 - 1e-9));
  }
  if (light.type == LightType::Directional) {
    out->wi = -light.direction;
    out->irradiance = light.irradiance;
    return !occluded({shadow_ray_origin(hit, out->wi), out->wi}, objects, 0.0, INFINITY);
  }
  return false;
}

}  // namespace clothbake::render

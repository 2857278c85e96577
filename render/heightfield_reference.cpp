// Ray-traced reference of a displaced cloth plane (heightfield_reference.hpp).
#include "render/heightfield_reference.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/error.hpp"
#include "eval/evaluator.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/writer/open_asset.hpp"
#include "formats/writer/valid_asset.hpp"
#include "raycast/heightfield_scene.hpp"
#include "render/camera.hpp"
#include "render/shapes.hpp"

namespace clothbake::render {

HeightfieldReference render_heightfield_reference(const Scene& scene, std::size_t index,
                                                  uint32_t s) {
  const auto start = std::chrono::steady_clock::now();
  if (index >= scene.objects.size())
    throw_input_error("near field: no object " + std::to_string(index));
  const Object& o = scene.objects[index];
  if (o.shape != ShapeType::Plane || o.asset.empty())
    throw_input_error(scene.path + ": " + o.name +
                      ": the near-field reference needs a plane "
                      "with a fabric");
  const reader::Asset asset = formats::open_valid_asset(o.asset);
  reader::FeatureMaps maps;
  eval::Evaluator ev;
  if (!reader::read_feature_maps(asset, &maps).ok() || !ev.open(asset).ok())
    throw_input_error(o.asset + ": cannot be opened for the near-field reference");
  const int n = int(maps.resolution);
  const std::vector<float> heights(maps.height.begin(), maps.height.end());
  float lo = heights[0], hi = heights[0];
  for (float v : heights)
    lo = std::min(lo, v), hi = std::max(hi, v);
  const raycast::PeriodicHeightField field(heights, n, raycast::automatic_rings(double(hi - lo)));
  const double z_top = field.z_max(), depth = field.z_max() - field.z_min();

  // The plane's frame, as shapes.cpp parameterises it; tile coordinates = surface units * tpu.
  const Vec3 nz = normalize(o.normal);
  const Vec3 tu = normalize(o.tangent - nz * dot(o.tangent, nz));
  const Vec3 tv = cross(nz, tu);
  const double tpu = o.tiles_per_unit;
  auto to_tile = [&](const Vec3& p) {
    const Vec3 d = p - o.center;
    return Vec3((dot(d, tu) + 0.5 * o.size[0]) * tpu, (dot(d, tv) + 0.5 * o.size[1]) * tpu,
                dot(d, nz) * tpu + z_top);
  };
  auto dir_to_tile = [&](const Vec3& d) { return Vec3(dot(d, tu), dot(d, tv), dot(d, nz)); };

  const PinholeCamera camera(scene.camera);
  const int w = scene.camera.width, h = scene.camera.height;
  HeightfieldReference out;
  out.image.width = w;
  out.image.height = h;
  out.image.rgb.assign(std::size_t(w) * h * 3, 0.0f);
  out.mask.assign(std::size_t(w) * h, 0);
  const double eps = 1e-6;
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int py = rows.begin(); py != rows.end(); ++py)
      for (int px = 0; px < w; ++px) {
        const SurfaceHit centre =
            intersect_scene(camera.generate(px + 0.5, py + 0.5).ray, scene.objects, 0.0, INFINITY);
        if (centre.object != int(index)) continue;
        out.mask[std::size_t(py) * w + px] = 1;
        Rgb sum;
        for (uint32_t j = 0; j < s; ++j)
          for (uint32_t i = 0; i < s; ++i) {
            const CameraRay cr = camera.generate(px + (i + 0.5) / s, py + (j + 0.5) / s);
            const SurfaceHit hit = intersect(cr.ray, o, 0.0, INFINITY);
            if (!std::isfinite(hit.t)) continue;  // the sub-ray misses the plane's extent
            const Vec3 p0 = to_tile(hit.point), d = dir_to_tile(cr.ray.direction);
            if (!(d.z < 0)) continue;  // seen from below: the relief faces up only
            const double t_max = (depth + 1e-3) / -d.z + 1.0;
            const raycast::SurfaceHit sh = field.first_hit(model::Vec3d(p0.x, p0.y, p0.z + eps),
                                                           model::Vec3d(d.x, d.y, d.z), t_max);
            const double t = sh.hit ? sh.t : (depth + eps) / -d.z;
            const Vec3 q = p0 + d * t;
            const int64_t tx = int64_t(std::floor(q.x * n)), ty = int64_t(std::floor(q.y * n));
            const double wo[3] = {-d.x, -d.y, -d.z};
            for (const Light& light : scene.lights) {
              Vec3 wi;
              Rgb irradiance;
              if (light.type == LightType::Point) {
                const Vec3 to = to_tile(light.position) - q;
                const double dist = length(to) / tpu;  // world units
                wi = normalize(to);
                irradiance = light.intensity / (dist * dist);
              } else if (light.type == LightType::Directional) {
                wi = dir_to_tile(-light.direction);
                irradiance = light.irradiance;
              } else {
                continue;  // environment lights: not in the near-field reference
              }
              if (!(wi.z > 0)) continue;
              // Shadow ray against the relief, up to above its top.
              const double ts = (depth + 1e-3) / wi.z + 1.0;
              const Vec3 lifted = q + wi * (2e-5 + 1e-4 / n);
              const bool blocked = field
                                       .first_hit(model::Vec3d(lifted.x, lifted.y, lifted.z),
                                                  model::Vec3d(wi.x, wi.y, wi.z), ts)
                                       .hit;
              const double wi_arr[3] = {wi.x, wi.y, wi.z};
              Rgb f;
              if (!ev.texel_value(tx, ty, wi_arr, wo, blocked ? 0.0 : 1.0,
                                  eval::kAllLobes & ~eval::lobe_bit(model::Lobe::DeltaTransmission),
                                  &f)
                       .ok())
                continue;
              sum += f * irradiance;
            }
          }
        const Rgb v = sum / double(s * s);
        float* px_out = &out.image.rgb[(std::size_t(py) * w + px) * 3];
        px_out[0] = float(v.r), px_out[1] = float(v.g), px_out[2] = float(v.b);
      }
  });
  out.image.stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.image.stats.passes = 1;
  return out;
}

}  // namespace clothbake::render

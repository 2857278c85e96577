// Usage analysis of a scene (usage_analysis.hpp).
#include "render/usage_analysis.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "formats/reader/radiance_query.hpp"
#include "model/directions.hpp"
#include "render/camera.hpp"
#include "render/environment.hpp"
#include "render/shading_frame.hpp"

namespace clothbake::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A spherical Fibonacci set: k directions spread evenly over the sphere (fixed, no randomness).
std::vector<Vec3> fibonacci_sphere(int k) {
  std::vector<Vec3> out;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < k; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / k, r = std::sqrt(std::max(0.0, 1.0 - z * z));
    out.push_back({r * std::cos(golden * i), r * std::sin(golden * i), z});
  }
  return out;
}

// One row's partial result for one object.
struct Partial {
  std::vector<float> sides;  // sqrt(area) per pixel
  double min_view_cos = 1, min_light_cos = 1, max_h_angle = 0;
  uint64_t grazing = 0, lit_same = 0, lit_opposite = 0;
  bool front = false, back = false;
  std::vector<uint8_t> bins, view_bins;
};

// The parallax look-up's view direction (reader::ParallaxView::view_direction on the mirrored
// view): normalised, below the cap moved onto its rim at the same azimuth.
model::Vec3d parallax_view(const Vec3& wo, double min_cos) {
  const double len = std::sqrt(wo.x * wo.x + wo.y * wo.y + wo.z * wo.z);
  double o[3] = {wo.x / len, wo.y / len, std::abs(wo.z) / len};
  if (o[2] < min_cos) {
    const double planar = std::sqrt(o[0] * o[0] + o[1] * o[1]);
    const double ax = planar > 0.0 ? o[0] / planar : 1.0, ay = planar > 0.0 ? o[1] / planar : 0.0;
    const double s = std::sqrt(1.0 - min_cos * min_cos);
    o[0] = ax * s;
    o[1] = ay * s;
    o[2] = min_cos;
  }
  return model::Vec3d(o[0], o[1], o[2]);
}

}  // namespace

uint64_t ObjectUsage::half_vector_bins_used() const {
  return uint64_t(std::count(half_vector_bins.begin(), half_vector_bins.end(), uint8_t(1)));
}

uint64_t ObjectUsage::view_bins_used() const {
  return uint64_t(std::count(view_bins.begin(), view_bins.end(), uint8_t(1)));
}

SceneUsage analyse_usage(const Scene& scene, const std::vector<FabricShape>& shapes) {
  SceneUsage out;
  out.max_error = scene.max_error;
  const std::size_t objects = scene.objects.size();
  out.objects.resize(objects);
  for (std::size_t k = 0; k < objects; ++k)
    out.objects[k].object = int(k);
  const PinholeCamera camera(scene.camera);
  const int w = scene.camera.width, h = scene.camera.height;

  // Light directions of the environment lights: the fixed set where the map is not black.
  struct EnvironmentLight {
    std::unique_ptr<Environment> env;
    std::vector<Vec3> directions;
  };
  std::vector<EnvironmentLight> environments(scene.lights.size());
  const std::vector<Vec3> sphere = fibonacci_sphere(kEnvironmentDirections);
  for (std::size_t li = 0; li < scene.lights.size(); ++li) {
    if (scene.lights[li].type != LightType::Environment) continue;
    environments[li].env = std::make_unique<Environment>(scene.lights[li].environment);
    for (const Vec3& d : sphere) {
      const Rgb l = environments[li].env->radiance(d);
      if (l.r > 0 || l.g > 0 || l.b > 0) environments[li].directions.push_back(d);
    }
  }

  // The scene's backdrop, when no environment light is the background, is seen through the gaps.
  const bool backdrop_behind =
      scene.background.max_component() > 0 &&
      std::none_of(scene.lights.begin(), scene.lights.end(),
                   [](const Light& l) { return l.type == LightType::Environment; });

  const std::vector<Partial> empty_row(objects);
  std::vector<std::vector<Partial>> rows(std::size_t(h), empty_row);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& range) {
    for (int py = range.begin(); py != range.end(); ++py) {
      std::vector<Partial>& row = rows[std::size_t(py)];
      for (int px = 0; px < w; ++px) {
        const CameraRay cr = camera.generate(px + 0.5, py + 0.5);
        const SurfaceHit hit = intersect_scene(cr.ray, scene.objects, 0.0, INFINITY);
        if (!hit.hit()) continue;
        const std::size_t k = std::size_t(hit.object);
        const FabricShape& shape = shapes[k];
        if (shape.resolution <= 0) continue;
        Partial& p = row[k];
        if (p.bins.empty() && shape.radiance_dirs > 0)
          p.bins.assign(std::size_t(shape.radiance_dirs) * std::size_t(shape.radiance_dirs), 0);
        const double scale = scene.objects[k].tiles_per_unit * shape.resolution;
        const reader::Footprint fp = footprint_rectangle(hit.u * scale, hit.v * scale,
                                                         surface_differentials(cr, hit), scale);
        p.sides.push_back(float(std::sqrt(std::max(0.0, (fp.x1 - fp.x0) * (fp.y1 - fp.y0)))));
        const ShadingFrame frame(hit);
        const Vec3 wo = frame.local(-cr.ray.direction);
        p.min_view_cos = std::min(p.min_view_cos, std::abs(wo.z));
        p.grazing += std::abs(wo.z) < kGrazingCos;
        if (shape.parallax_dirs > 0 && length(wo) > 0) {
          if (p.view_bins.empty())
            p.view_bins.assign(std::size_t(shape.parallax_dirs) * std::size_t(shape.parallax_dirs),
                               0);
          const model::DirectionGrid<double> grid{shape.parallax_dirs, shape.parallax_min_cos};
          const model::BinBilinear<double> b =
              grid.bilinear_fast(parallax_view(wo, shape.parallax_min_cos));
          for (int j = 0; j < 4; ++j)
            if (b.weight[j] > 0.0) p.view_bins[std::size_t(b.index[j])] = 1;
        }
        (wo.z >= 0 ? p.front : p.back) = true;
        // One unshadowed light direction (world): counts its side and marks its half vector.
        auto lit = [&](const Vec3& wi_world) {
          const Vec3 wi = frame.local(wi_world);
          if (wi.z * wo.z >= 0)
            ++p.lit_same;
          else
            ++p.lit_opposite;
          p.min_light_cos = std::min(p.min_light_cos, std::abs(wi.z));
          Vec3 hv = wi + wo;
          if (!(length(hv) > 1e-12)) return;  // i = -o: the delta lobe, no half-vector bin
          if (hv.z < 0) hv = -hv;             // folded as the tables fold it
          p.max_h_angle =
              std::max(p.max_h_angle, std::acos(std::clamp(hv.z / length(hv), -1.0, 1.0)));
          if (p.bins.empty()) return;
          const double harr[3] = {hv.x, hv.y, hv.z};
          reader::BinWeights bw;
          if (!reader::make_bin_weights(uint32_t(shape.radiance_dirs), harr, &bw)) return;
          for (uint32_t j = 0; j < bw.count; ++j)
            if (bw.weight[j] > 0) p.bins[bw.bin[j]] = 1;
        };
        for (std::size_t li = 0; li < scene.lights.size(); ++li) {
          const Light& light = scene.lights[li];
          if (light.type != LightType::Environment) {
            LightArrival arrival;
            if (unshadowed_light(light, hit, scene.objects, &arrival)) lit(arrival.wi);
          } else {
            for (const Vec3& wi : environments[li].directions)
              if (!occluded({shadow_ray_origin(hit, wi), wi}, scene.objects, 0.0, INFINITY))
                lit(wi);
            // The delta lobe looks straight through the gaps at the environment behind.
            const Vec3 behind = cr.ray.direction;
            const Rgb l = environments[li].env->radiance(behind);
            if ((l.r > 0 || l.g > 0 || l.b > 0) &&
                !occluded({shadow_ray_origin(hit, behind), behind}, scene.objects, 0.0, INFINITY))
              ++p.lit_opposite;
          }
        }
        // The backdrop through the gaps: the delta lobe as well.
        if (backdrop_behind &&
            !occluded({shadow_ray_origin(hit, cr.ray.direction), cr.ray.direction}, scene.objects,
                      0.0, INFINITY))
          ++p.lit_opposite;
      }
    }
  });

  // Merge in row order (deterministic).
  for (std::size_t k = 0; k < objects; ++k) {
    ObjectUsage& u = out.objects[k];
    std::vector<float> sides;
    uint64_t grazing = 0;
    for (const auto& row : rows) {
      const Partial& p = row[k];
      sides.insert(sides.end(), p.sides.begin(), p.sides.end());
      u.min_view_cos = std::min(u.min_view_cos, p.min_view_cos);
      u.min_light_cos = std::min(u.min_light_cos, p.min_light_cos);
      u.max_half_vector_angle = std::max(u.max_half_vector_angle, p.max_h_angle);
      grazing += p.grazing;
      u.lit_same_side += p.lit_same;
      u.lit_opposite_side += p.lit_opposite;
      u.views_front = u.views_front || p.front;
      u.views_back = u.views_back || p.back;
      if (!p.bins.empty()) {
        if (u.half_vector_bins.empty()) u.half_vector_bins.assign(p.bins.size(), 0);
        for (std::size_t b = 0; b < p.bins.size(); ++b)
          u.half_vector_bins[b] |= p.bins[b];
      }
      if (!p.view_bins.empty()) {
        if (u.view_bins.empty()) u.view_bins.assign(p.view_bins.size(), 0);
        for (std::size_t b = 0; b < p.view_bins.size(); ++b)
          u.view_bins[b] |= p.view_bins[b];
      }
    }
    u.pixels = sides.size();
    if (sides.empty()) continue;
    std::sort(sides.begin(), sides.end());
    u.footprint_min = sides.front();
    u.footprint_max = sides.back();
    u.footprint_p05 = sides[sides.size() / 20];
    u.footprint_median = sides[sides.size() / 2];
    u.grazing_view_fraction = double(grazing) / double(sides.size());
  }
  return out;
}

}  // namespace clothbake::render

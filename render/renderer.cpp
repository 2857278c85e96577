// The direct-lighting renderer (renderer.hpp).
#include "render/renderer.hpp"

#include <sys/stat.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "common/error.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/writer/open_asset.hpp"
#include "formats/writer/valid_asset.hpp"
#include "model/splitmix64.hpp"
#include "render/camera.hpp"
#include "render/environment.hpp"
#include "render/shading_frame.hpp"
#include "render/shapes.hpp"

namespace clothbake::render {
namespace {

// The least strata a side of an edge pixel's path-traced rays (RenderOptions::jitter_edges), on a
// boundary (a silhouette or a shadow edge: Renderer::pixel_kinds) and where only the view turns.
// A boundary pixel's error is mostly the texture's point-sample noise on either side (a control
// variate for the coverage alone, the centre's footprint estimate on the rays that hit its object,
// changed nothing), and with the interior's estimate far below it the boundaries carried most of a
// scene's error: 12 x 12 there took the goose-eye cushion from 3.5x to 16.6x brute-path's speed at
// equal error, the room from 15.6x to 17.2x, the chair from 20.1x to 20.7x and the far satin
// sphere from 27.5x to 28.4x; 16 x 16 lost on the sphere (21.6x) and the chair (17.3x), and 12 x
// 12 on the view's turns too cost the far satin sphere two thirds more time for a fifth less
// error (25.3-26.7x) (docs/performance.md, "Edges' strata"). Earlier, on the far satin
// sphere, 8 x 8 point rays took half the time of 8 x 8 rays with footprints for a third more
// 2-spp error.
constexpr uint64_t kBoundaryStrata = 12, kViewTurnStrata = 8;
// Its rays per spp beyond those: with 16, 32 or 64 the error-time curves of the satin sphere and
// the room lay on one frontier from 4 to 256 spp; with spp rays (a side of sqrt(spp)) the edges
// held the error at its 2-spp value up to 64 spp (docs/performance.md, "Scenes against the
// path-traced truth").
constexpr double kEdgeRaysPerSpp = 32;
// A cloth pixel is interior only if its five view cosines are all at least this fraction of the
// largest (Renderer::interior_pixels): below it, the centre's directions misstate the pixel's
// average (docs/rendering.md, "Edge pixels").
constexpr double kInteriorCosineRatio = 0.7;
// Renderer::pixel_kinds' codes.
constexpr uint8_t kBoundaryPixel = 0, kInteriorPixel = 1, kViewTurnPixel = 2;

constexpr double kPi = 3.14159265358979323846;
constexpr eval::LobeMask kDeltaBit = eval::lobe_bit(model::Lobe::DeltaTransmission);
constexpr eval::LobeMask kContinuousLobes = eval::kAllLobes & ~kDeltaBit;

// An opened asset and its evaluator, shared by every object that names the same file (5000
// objects of one asset hold it once: docs/hardening.md, "Limits").
struct OpenedAsset {
  reader::Asset asset;
  eval::Evaluator evaluator;
};

// An object's shading: an opened asset and its evaluator, or a Lambertian colour.
struct Material {
  std::shared_ptr<const OpenedAsset> opened;
  const eval::Evaluator* evaluator = nullptr;  // &opened->evaluator
  bool cloth = false;
  double texels_per_unit = 0;  // tiles_per_unit * N
};

// The file's identity (device, inode), or its path when it cannot be read (opening then fails).
std::string file_identity(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return "path " + path;
  return std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
}

using Frame = ShadingFrame;

uint64_t pixel_seed(uint64_t seed, uint32_t pass, uint64_t pixel) {
  uint64_t s = seed ^ 0x243f6a8885a308d3ull;
  model::splitmix64_next(s);
  s ^= (uint64_t(pass) << 40) ^ pixel;
  return model::splitmix64_next(s);
}

struct Counters {
  std::atomic<uint64_t> estimates{0}, texel_evals{0}, samples{0}, direct{0}, cloth_pixels{0};
  std::atomic<uint64_t> without_control_variate{0}, remainder_samples{0}, visibility_samples{0};
  std::atomic<uint64_t> out_of_plan{0}, fallback_brute{0}, fallback_zero{0};
  std::mutex mutex;
  double min_texels = INFINITY, max_texels = 0;
};

}  // namespace

struct Renderer::Impl {
  PinholeCamera camera;
  std::vector<Material> materials;
  std::vector<std::unique_ptr<Environment>> environments;  // per light (null if not environment)
  const Environment* background = nullptr;
  // Some object's asset is scene-planned: it holds what the pixel centres query (the usage
  // analysis traces centres), so edge pixels are not jittered (RenderOptions::jitter_edges).
  bool planned = false;
  explicit Impl(const Camera& c) : camera(c) {}
};

Renderer::Renderer(const Scene& scene, const RenderOptions& options)
    : scene_(scene), options_(options), impl_(std::make_unique<Impl>(scene.camera)) {
  std::map<std::string, std::shared_ptr<const OpenedAsset>> opened;  // by file identity
  for (const Object& o : scene.objects) {
    Material m;
    if (!o.asset.empty()) {
      std::shared_ptr<const OpenedAsset>& shared = opened[file_identity(o.asset)];
      if (!shared) {
        auto fresh = std::make_shared<OpenedAsset>();
        fresh->asset = formats::open_valid_asset(o.asset);
        eval::EvalOptions eo;
        eo.tables = options.tables;
        eo.parallax = options.parallax;
        eo.sheen_convention = options.sheen_convention;
        formats::throw_if_failed(fresh->evaluator.open(fresh->asset, eo),
                                 scene.path + ": " + o.name + ".asset: " + o.asset);
        shared = std::move(fresh);
      }
      reader::ScenePlanRecord plan;
      bool planned = false;
      impl_->planned |= reader::read_scene_plan(shared->asset, &plan, &planned).ok() && planned;
      m.opened = shared;
      m.evaluator = &shared->evaluator;
      m.cloth = true;
      m.texels_per_unit = o.tiles_per_unit * m.evaluator->resolution();
    }
    impl_->materials.push_back(std::move(m));
  }
  for (const Light& l : scene.lights) {
    if (l.type == LightType::Environment) {
      impl_->environments.push_back(std::make_unique<Environment>(l.environment));
      if (!impl_->background) impl_->background = impl_->environments.back().get();
    } else {
      impl_->environments.push_back(nullptr);
    }
  }
}

Renderer::~Renderer() = default;

PixelFootprint Renderer::pixel_footprint(int px, int py) const {
  PixelFootprint out;
  const CameraRay cr = impl_->camera.generate(px + 0.5, py + 0.5);
  const SurfaceHit hit = intersect_scene(cr.ray, scene_.objects, 0.0, INFINITY);
  if (!hit.hit()) return out;
  out.object = hit.object;
  const Frame frame(hit);
  const Vec3 wo = frame.local(-cr.ray.direction);
  out.wo[0] = wo.x, out.wo[1] = wo.y, out.wo[2] = wo.z;
  const Material& m = impl_->materials[std::size_t(hit.object)];
  const double scale =
      m.cloth ? m.texels_per_unit : scene_.objects[std::size_t(hit.object)].tiles_per_unit;
  out.rect =
      footprint_rectangle(hit.u * scale, hit.v * scale, surface_differentials(cr, hit), scale);
  return out;
}

std::vector<uint8_t> Renderer::interior_pixels() const {
  std::vector<uint8_t> mask = pixel_kinds();
  for (uint8_t& m : mask)
    m = m == kInteriorPixel;
  return mask;
}

std::vector<uint8_t> Renderer::pixel_kinds() const {
  const int w = impl_->camera.width(), h = impl_->camera.height();
  // What a point of the image sees: the object hit (-1: none) and, per point or directional light
  // (the first 64), whether it is shadowed there; at the (w + 1) x (h + 1) pixel corners each
  // traced once.
  struct Seen {
    int object = -1;
    uint64_t shadowed = 0;
    double cos_view = 0;  // |cos| between the (unit) ray and the unit geometric normal
    bool same_surface(const Seen& o) const { return object == o.object && shadowed == o.shadowed; }
  };
  auto seen_at = [&](double x, double y) {
    const Ray ray = impl_->camera.generate(x, y).ray;
    const SurfaceHit hit = intersect_scene(ray, scene_.objects, 0.0, INFINITY);
    Seen seen;
    if (!hit.hit()) return seen;
    seen.object = hit.object;
    seen.cos_view = std::abs(dot(hit.normal, ray.direction));
    for (std::size_t li = 0; li < scene_.lights.size() && li < 64; ++li) {
      LightArrival arrival;
      if (scene_.lights[li].type != LightType::Environment &&
          !unshadowed_light(scene_.lights[li], hit, scene_.objects, &arrival))
        seen.shadowed |= uint64_t(1) << li;
    }
    return seen;
  };
  std::vector<Seen> corner(std::size_t(w + 1) * std::size_t(h + 1));
  tbb::parallel_for(0, h + 1, [&](int y) {
    for (int x = 0; x <= w; ++x)
      corner[std::size_t(y) * std::size_t(w + 1) + std::size_t(x)] = seen_at(x, y);
  });
  std::vector<uint8_t> mask(std::size_t(w) * std::size_t(h));
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const Seen c = seen_at(x + 0.5, y + 0.5);
      const std::size_t k = std::size_t(y) * std::size_t(w + 1) + std::size_t(x);
      const Seen* corners[4] = {&corner[k], &corner[k + 1], &corner[k + std::size_t(w) + 1],
                                &corner[k + std::size_t(w) + 2]};
      bool interior = true;
      double least = c.cos_view, most = c.cos_view;
      for (const Seen* q : corners) {
        interior = interior && q->same_surface(c);
        least = std::min(least, q->cos_view);
        most = std::max(most, q->cos_view);
      }
      // The view's turn matters where a footprint takes the centre's directions: on cloth (a
      // Lambertian object is shaded at the centre's hit whatever the view).
      const bool cloth = c.object >= 0 && impl_->materials[std::size_t(c.object)].cloth;
      mask[std::size_t(y) * std::size_t(w) + std::size_t(x)] =
          !interior
              ? kBoundaryPixel
              : (!cloth || least >= kInteriorCosineRatio * most ? kInteriorPixel : kViewTurnPixel);
    }
  });
  return mask;
}

RenderResult Renderer::render(const std::function<void(double)>& progress) const {
  return render(options_, progress);
}

RenderResult Renderer::render(const RenderOptions& pass_options,
                              const std::function<void(double)>& progress) const {
  if (pass_options.tables != options_.tables || pass_options.parallax != options_.parallax ||
      pass_options.sheen_convention != options_.sheen_convention)
    throw std::invalid_argument(
        "Renderer::render: the tables, parallax and sheen convention are the constructor's");
  const auto start = std::chrono::steady_clock::now();
  const Scene& scene = scene_;
  const Impl& impl = *impl_;
  const int w = scene.camera.width, h = scene.camera.height;
  RenderResult result;
  result.width = w;
  result.height = h;
  std::vector<double> sum(std::size_t(w) * h * 3, 0.0);
  Counters counters;
  const uint32_t spp = pass_options.spp;

  // The backdrop, when no environment light is the background, is seen through the gaps.
  const bool backdrop_behind = !impl.background && scene.background.max_component() > 0;
  // The direct lighting at the primary hit of camera ray (x, y) (image coordinates), with `spp`
  // evaluator samples over the pixel's footprint, or at the hit's point when path tracing.
  // The method that evaluates an edge pixel's rays at their points: brute force's one sample (one
  // view bin drawn) where the method asked for would evaluate a point exactly (multiscale,
  // multiscale-paper: all four view bins, up to four texel evaluations); at equal error it took
  // less time (docs/performance.md, "Scenes against the path-traced truth"). The reference stays
  // exact.
  const eval::Method edge_method = pass_options.method == eval::Method::Reference
                                       ? eval::Method::Reference
                                       : eval::Method::Brute;
  auto shade_ray = [&](double x, double y, uint32_t samples, bool point, eval::Method method,
                       eval::Rng& rng, bool first_pass) -> Rgb {
    const CameraRay cr = impl.camera.generate(x, y);
    const SurfaceHit hit = intersect_scene(cr.ray, scene.objects, 0.0, INFINITY);
    if (!hit.hit())
      return impl.background ? impl.background->radiance(cr.ray.direction) : scene.background;
    const Object& object = scene.objects[std::size_t(hit.object)];
    const Material& m = impl.materials[std::size_t(hit.object)];
    const Frame frame(hit);
    const Vec3 wo_world = -cr.ray.direction;
    const Vec3 wo = frame.local(wo_world);
    const double wo_arr[3] = {wo.x, wo.y, wo.z};
    reader::Footprint fp{};
    if (m.cloth) {
      const double tu = hit.u * m.texels_per_unit, tv = hit.v * m.texels_per_unit;
      fp = point ? reader::Footprint{tu, tv, tu, tv}
                 : footprint_rectangle(tu, tv, surface_differentials(cr, hit), m.texels_per_unit);
      counters.cloth_pixels.fetch_add(first_pass ? 1 : 0, std::memory_order_relaxed);
      if (first_pass && !point) {
        const double texels = (fp.x1 - fp.x0) * (fp.y1 - fp.y0);
        std::lock_guard lock(counters.mutex);
        counters.min_texels = std::min(counters.min_texels, texels);
        counters.max_texels = std::max(counters.max_texels, texels);
      }
    }
    auto shadow_origin = [&](const Vec3& wi) { return shadow_ray_origin(hit, wi); };
    // The integrand of the rendering equation for light from world direction wi: f^ V |cos|.
    auto bsdf = [&](const Vec3& wi_world, eval::LobeMask mask, uint32_t samples) -> Rgb {
      const Vec3 wi = frame.local(wi_world);
      if (!m.cloth) {
        if (!(wi.z * wo.z > 0)) return {};
        return object.diffuse * (std::abs(wi.z) / kPi);
      }
      const double wi_arr[3] = {wi.x, wi.y, wi.z};
      eval::Estimate e;
      reader::Status s = m.evaluator->estimate(fp, wi_arr, wo_arr, method, samples, rng, mask, &e);
      if (s.code() == reader::ErrorCode::OutOfPlan) {
        // A scene-planned asset left out what this query needs (docs/scene-plans.md,
        // "Queries outside the plan"): brute force over the same footprint needs no table; when
        // it is refused too (a view bin or transmission left out), the light contributes 0.
        counters.out_of_plan.fetch_add(1, std::memory_order_relaxed);
        if (method != eval::Method::Brute && method != eval::Method::Reference)
          s = m.evaluator->estimate(fp, wi_arr, wo_arr, eval::Method::Brute, samples, rng, mask,
                                    &e);
        if (s.ok())
          counters.fallback_brute.fetch_add(1, std::memory_order_relaxed);
        else
          counters.fallback_zero.fetch_add(1, std::memory_order_relaxed);
      }
      counters.estimates.fetch_add(1, std::memory_order_relaxed);
      counters.texel_evals.fetch_add(e.counters.texel_evals, std::memory_order_relaxed);
      counters.samples.fetch_add(e.counters.samples, std::memory_order_relaxed);
      if (e.counters.direct) counters.direct.fetch_add(1, std::memory_order_relaxed);
      if (e.counters.without_control_variate)
        counters.without_control_variate.fetch_add(1, std::memory_order_relaxed);
      counters.remainder_samples.fetch_add(e.counters.remainder_samples, std::memory_order_relaxed);
      counters.visibility_samples.fetch_add(e.counters.visibility_samples,
                                            std::memory_order_relaxed);
      return s.ok() ? e.value : Rgb();
    };
    // A BSDF-sampled direction and its density (continuous techniques only).
    auto bsdf_pdf = [&](const Vec3& wi_world) -> double {
      const Vec3 wi = frame.local(wi_world);
      if (!m.cloth) return wi.z * wo.z > 0 ? std::abs(wi.z) / kPi : 0.0;
      const double wi_arr[3] = {wi.x, wi.y, wi.z};
      double pdf = 0;
      return m.evaluator->direction_pdf(fp, wi_arr, wo_arr, &pdf).ok() ? pdf : 0.0;
    };

    Rgb radiance;
    for (std::size_t li = 0; li < scene.lights.size(); ++li) {
      const Light& light = scene.lights[li];
      if (light.type != LightType::Environment) {
        LightArrival arrival;
        if (unshadowed_light(light, hit, scene.objects, &arrival))
          radiance += bsdf(arrival.wi, kContinuousLobes, samples) * arrival.irradiance;
      } else {
        const Environment& env = *impl.environments[li];
        Rgb sum_env;
        for (uint32_t k = 0; k < samples; ++k) {
          // Light sample, weighted by the balance heuristic against the BSDF density.
          double p_light = 0;
          const Vec3 wl = env.sample(rng.uniform(), rng.uniform(), &p_light);
          if (p_light > 0 && !occluded({shadow_origin(wl), wl}, scene.objects, 0.0, INFINITY)) {
            const double p_bsdf = bsdf_pdf(wl);
            sum_env += bsdf(wl, kContinuousLobes, 1) * env.radiance(wl) / (p_light + p_bsdf);
          }
          // BSDF sample, the same heuristic.
          Vec3 wb;
          double p_bsdf = 0;
          bool delta = false, valid = false;
          const double ul = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
          if (m.cloth) {
            eval::Evaluator::DirectionSample ds;
            if (m.evaluator->sample_direction(fp, wo_arr, ul, u1, u2, &ds).ok() && ds.valid) {
              valid = true;
              delta = ds.is_delta;
              wb = frame.world(Vec3(ds.wi[0], ds.wi[1], ds.wi[2]));
              p_bsdf = ds.pdf;
            }
          } else {
            // Cosine-weighted on the viewer's side.
            const double r = std::sqrt(u1), phi = 2 * kPi * u2;
            const double z = std::sqrt(std::max(0.0, 1 - u1)) * (wo.z >= 0 ? 1 : -1);
            wb = frame.world(Vec3(r * std::cos(phi), r * std::sin(phi), z));
            p_bsdf = std::abs(z) / kPi;
            valid = p_bsdf > 0;
          }
          if (valid && !delta && p_bsdf > 0 &&
              !occluded({shadow_origin(wb), wb}, scene.objects, 0.0, INFINITY)) {
            const double pl = env.pdf(wb);
            sum_env += bsdf(wb, kContinuousLobes, 1) * env.radiance(wb) / (pl + p_bsdf);
          }
        }
        radiance += sum_env / double(samples);
        // The delta lobe: the environment straight through the gaps, V T_sheen (1 - I) L(-o).
        if (m.cloth &&
            !occluded({shadow_origin(-wo_world), -wo_world}, scene.objects, 0.0, INFINITY))
          radiance += bsdf(-wo_world, kDeltaBit, samples) * env.radiance(-wo_world);
      }
    }
    // The scene's backdrop straight through the gaps, as an environment's above (it lights nothing
    // else: it is not a light).
    if (m.cloth && backdrop_behind &&
        !occluded({shadow_origin(-wo_world), -wo_world}, scene.objects, 0.0, INFINITY))
      radiance += bsdf(-wo_world, kDeltaBit, samples) * scene.background;
    return radiance;
  };
  std::atomic<uint64_t> edge_pixels{0};
  // The interior pixels; a footprint method path traces the others (the edges) from stratified
  // rays (RenderOptions::jitter_edges). Computed in every render: its time is the render's.
  const std::vector<uint8_t> interior =
      !pass_options.path_traced && pass_options.jitter_edges && !impl.planned
          ? pixel_kinds()
          : std::vector<uint8_t>();
  // One pixel of pass `pass`: the pixel centre's footprint, or jittered rays each evaluated at its
  // hit's point (path tracing: spp rays; an edge pixel: s x s stratified rays).
  auto shade = [&](int px, int py, uint32_t pass) -> Rgb {
    const uint64_t pixel = uint64_t(py) * w + px;
    eval::Rng rng(pixel_seed(pass_options.seed, pass, pixel));
    if (pass_options.path_traced) {
      Rgb sum;
      for (uint32_t k = 0; k < spp; ++k) {
        const double u = rng.uniform(), v = rng.uniform();
        sum += shade_ray(px + u, py + v, 1, true, pass_options.method, rng, pass == 0 && k == 0);
      }
      return sum / double(spp);
    }
    if (interior.empty() || interior[pixel] == kInteriorPixel)
      return shade_ray(px + 0.5, py + 0.5, spp, false, pass_options.method, rng, pass == 0);
    // An edge pixel: s x s stratified rays, s = max(12 on a boundary, 8 on a view's turn,
    // ceil(sqrt(32 spp))): 32 point rays per
    // spp keep its error falling with spp as the interior's does (with sqrt(spp) a side it stayed
    // at its 8 x 8 error up to 64 spp; docs/performance.md). Its value jumps between
    // surfaces (or light and shadow) across the pixel, or its directions turn, so the centre's
    // footprint misstates it and a few uniform rays would make it the noisiest pixel of the image;
    // strata over the pixel's area bring that noise down faster than more rays alone would. Each
    // ray is evaluated at its point: a footprint per ray lowered the error a little at several
    // times the cost (docs/performance.md). 64-bit: s reaches 65 536 at the largest spp.
    if (pass == 0) edge_pixels.fetch_add(1, std::memory_order_relaxed);
    const uint64_t s =
        std::max<uint64_t>(interior[pixel] == kBoundaryPixel ? kBoundaryStrata : kViewTurnStrata,
                           uint64_t(std::ceil(std::sqrt(kEdgeRaysPerSpp * double(spp)))));
    // Each stratum its own generator, so that what one ray's shading draws (which depends on the
    // scene: a black backdrop skips the gaps' lobe) does not move the next ray's samples.
    Rgb sum;
    for (uint64_t j = 0; j < s; ++j)
      for (uint64_t i = 0; i < s; ++i) {
        uint64_t state = pixel_seed(pass_options.seed, pass, pixel) ^ ((j * s + i + 1) << 40);
        eval::Rng stratum(model::splitmix64_next(state));
        const double u = (i + stratum.uniform()) / s, v = (j + stratum.uniform()) / s;
        sum +=
            shade_ray(px + u, py + v, 1, true, edge_method, stratum, pass == 0 && i == 0 && j == 0);
      }
    return sum / double(s * s);
  };

  // Pixels go in 8 x 8 tiles, a tile per task: neighbouring pixels share view bins, half-vector
  // bins and parallax planes, so a tile's estimates read what the cache already holds (a row of
  // 128 pixels touches about 40 view directions; a tile about 9). Every pixel has its own seed:
  // the image does not depend on the order or the thread count.
  constexpr int kTile = 8;
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  std::atomic<uint64_t> pixels_done{0};
  uint32_t pass = 0;
  do {
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y, 1),
                      [&](const tbb::blocked_range<int>& tiles) {
                        for (int tile = tiles.begin(); tile != tiles.end(); ++tile) {
                          const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
                          const int x1 = std::min(w, x0 + kTile), y1 = std::min(h, y0 + kTile);
                          for (int py = y0; py < y1; ++py)
                            for (int px = x0; px < x1; ++px) {
                              const Rgb c = shade(px, py, pass);
                              double* out = &sum[(std::size_t(py) * w + px) * 3];
                              out[0] += c.r;
                              out[1] += c.g;
                              out[2] += c.b;
                            }
                          const uint64_t done =
                              pixels_done.fetch_add(uint64_t(x1 - x0) * (y1 - y0)) +
                              uint64_t(x1 - x0) * (y1 - y0);
                          if (progress && pass_options.time_budget <= 0)
                            progress(double(done) / (double(w) * h));
                        }
                      });
    ++pass;
    if (progress && pass_options.time_budget > 0) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      progress(std::min(1.0, elapsed / pass_options.time_budget));
    }
  } while (pass_options.time_budget > 0 &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() <
               pass_options.time_budget);

  result.rgb.resize(sum.size());
  for (std::size_t k = 0; k < sum.size(); ++k)
    result.rgb[k] = float(sum[k] / pass);
  RenderStats& st = result.stats;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  st.passes = pass;
  st.estimates = counters.estimates;
  st.texel_evals = counters.texel_evals;
  st.samples = counters.samples;
  st.direct = counters.direct;
  st.without_control_variate = counters.without_control_variate;
  st.remainder_samples = counters.remainder_samples;
  st.visibility_samples = counters.visibility_samples;
  st.out_of_plan = counters.out_of_plan;
  st.fallback_brute = counters.fallback_brute;
  st.fallback_zero = counters.fallback_zero;
  st.cloth_pixels = counters.cloth_pixels;
  st.edge_pixels = edge_pixels;
  st.footprint_texels_min = std::isfinite(counters.min_texels) ? counters.min_texels : 0;
  st.footprint_texels_max = counters.max_texels;
  const NegativePixels negative = count_negative_pixels(result.rgb);
  st.negative_pixels = negative.count;
  st.min_value = negative.least;
  return result;
}

NegativePixels count_negative_pixels(const std::vector<float>& rgb) noexcept {
  NegativePixels out;
  for (std::size_t p = 0; p + 2 < rgb.size(); p += 3) {
    const float least = std::min({rgb[p], rgb[p + 1], rgb[p + 2]});
    if (least < 0.0f) {
      ++out.count;
      out.least = std::min(out.least, double(least));
    }
  }
  return out;
}

}  // namespace clothbake::render

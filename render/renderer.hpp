// A small direct-lighting renderer over the evaluator (docs/rendering.md): one primary ray through
// each pixel centre (path-traced rays over the pixel on edges, RenderOptions::jitter_edges), its
// footprint in texel space from ray differentials, every light sampled with
// a shadow ray, cloth shaded by eval::Evaluator::estimate over the pixel's footprint, Lambertian
// surfaces where an object has no asset. Environment lights combine light sampling and BSDF
// importance sampling (Sec. 5.1) by multiple importance sampling (balance heuristic, one sample of
// each per pixel sample); point and directional lights are sampled exactly. The delta lobe shows
// the environment straight through the cloth's gaps.
//
// Determinism: every pixel draws from its own generator, seeded from (seed, pass, pixel index), and
// the pixels are independent: the image is bit-identical for any thread count (TBB, rows in
// parallel; the caller caps the threads with tbb::global_control).
//
// C++20. Construction opens every asset and throws clothbake::Error naming the object (Input for a
// missing file or section, InvalidAsset for a corrupt one); render() does not throw.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "eval/evaluator.hpp"
#include "render/scene.hpp"

namespace clothbake::render {

struct RenderOptions {
  eval::Method method = eval::Method::Multiscale;
  uint32_t spp = 2;  // evaluator samples per footprint, and light/BSDF sample pairs for
                     // environment lights, per pixel and pass
  uint64_t seed = 1;
  double time_budget = 0;  // seconds: render passes of `spp` until the budget is spent (at least
                           // one); 0: one pass
  // Path tracing instead of footprints: each of the spp samples is a camera ray jittered over the
  // pixel, with its own hit, its own shadow rays and the method evaluated at the hit's point (one
  // sample: brute force then pays one BSDF evaluation per ray), as a path tracer without a
  // multi-scale model renders (docs/rendering.md, "Path-traced brute force").
  bool path_traced = false;
  // Footprint methods: a pixel on a silhouette, a shadow edge or a turn of the view across cloth
  // (Renderer::interior_pixels() 0) is path traced, as `path_traced` renders every pixel, from
  // s x s camera rays stratified over its area, s = max(12 on a silhouette or shadow edge, 8 where
  // only the view turns, ceil(sqrt(32 spp))), each evaluated at
  // its hit's point with one brute-force sample (the reference method: exactly), instead of from
  // its centre's footprint, so that it converges to the pixel's area average as path tracing does
  // (docs/rendering.md, "Edge pixels"). The edge test is part of each render's time. false: every
  // pixel from its centre (the reference of the reports, which is compared off the edges only).
  // Ignored (centres) when an object's asset is scene-planned: such an asset holds what the pixel
  // centres query.
  bool jitter_edges = true;
  eval::TableChoice tables = eval::TableChoice::Auto;
  bool parallax = true;  // false: the model without parallax offsets (near-field comparison)
  // The sheen table (docs/sheen.md): the published one by default, as other renderers use.
  model::SheenConvention sheen_convention = model::SheenConvention::Published;
};

struct RenderStats {
  double seconds = 0;  // wall time of render()
  uint32_t passes = 0;
  uint64_t estimates = 0;  // evaluator calls
  uint64_t texel_evals = 0, samples = 0, direct = 0;
  uint64_t without_control_variate = 0;  // multiscale estimates sampled as brute force
  uint64_t remainder_samples = 0;  // multiscale: cheap samples of g over the footprints' remainders
  uint64_t visibility_samples = 0;  // multiscale: samples of the visibility correction
  uint64_t cloth_pixels = 0;
  // Pixels path traced as edges (RenderOptions::jitter_edges; 0 with centres or path tracing).
  // Their rays' evaluations are in estimates, samples and texel_evals: one each a light and ray.
  uint64_t edge_pixels = 0;
  // Scene-planned assets: estimates refused as OutOfPlan, of which answered by brute force (the
  // fallback) and counted as 0 (refused again: a view bin or transmission left out).
  uint64_t out_of_plan = 0, fallback_brute = 0, fallback_zero = 0;
  // Over the cloth pixels shaded from a footprint (0 when none: path tracing).
  double footprint_texels_min = 0, footprint_texels_max = 0;
  // Pixels with a channel below 0 and the least channel value (0 when none): the unbiased
  // multi-scale and brute-force estimates are noisy around the exact value, and a residual
  // f - g can push a dark pixel below 0 (docs/rendering.md, "Negative pixels").
  uint64_t negative_pixels = 0;
  double min_value = 0;
};

// The pixels of an RGB image (3 floats a pixel) with a channel below 0, and the least channel
// among them (0 when there are none): RenderStats::negative_pixels and min_value. No allocation.
struct NegativePixels {
  uint64_t count = 0;
  double least = 0;
};
NegativePixels count_negative_pixels(const std::vector<float>& rgb) noexcept;

struct RenderResult {
  int width = 0, height = 0;
  std::vector<float> rgb;  // width * height * 3, linear radiance, row 0 at the top
  RenderStats stats;
};

// Per-pixel geometry of the primary hit (for usage analysis and tests): the object hit (-1:
// background), its footprint in texels and the local view direction.
struct PixelFootprint {
  int object = -1;
  reader::Footprint rect;
  double wo[3] = {0, 0, 1};
};

class Renderer {
 public:
  // Keeps a reference to `scene`: it must outlive the renderer and stay unchanged while it lives
  // (the camera, objects and lights are read at construction and at every render).
  Renderer(const Scene& scene, const RenderOptions& options);
  Renderer(Scene&&, const RenderOptions&) = delete;  // a temporary scene would dangle
  ~Renderer();

  // Renders the image; `progress(fraction)` is called from the rendering threads (thread-safe,
  // cheap).
  RenderResult render(const std::function<void(double)>& progress = {}) const;

  // The same with another method, spp, seed and time budget (those of `pass`) on the assets this
  // renderer opened, so that what the evaluators build on first use (the parallax planes of the
  // views met, per-bin tables) is built once, as a renderer keeps its assets between frames. The
  // image is the one a new Renderer(scene, pass) renders. Throws std::invalid_argument when
  // pass's tables, parallax or sheen convention differ from the constructor's.
  RenderResult render(const RenderOptions& pass,
                      const std::function<void(double)>& progress = {}) const;

  // The primary hit of pixel (x, y): object, texel footprint and view direction in the object's
  // shading frame (docs/rendering.md, "Pixel footprints").
  PixelFootprint pixel_footprint(int x, int y) const;

  // One byte per pixel, row 0 at the top: 1 where the camera rays through the pixel's centre and
  // its four corners all hit the same object (or all miss), at the hits the same point and
  // directional lights (the first 64) are shadowed, and, on cloth, the five |cosines| between the
  // rays and the geometric normal are all at least kInteriorCosineRatio (0.7) times the largest;
  // 0 on silhouettes, shadow edges and where the view turns across a cloth pixel (inside a curved
  // object's outline, or a plane seen within a few pixels of its horizon). A footprint renders a
  // pixel from its centre's hit, directions and shadow rays while path tracing averages them over
  // the pixel's area, so the two converge to different values there (docs/rendering.md, "Edge
  // pixels"; changes of the light's direction across a pixel are not tested). Traces (1 + lights)
  // rays per pixel and corner, in parallel (TBB); allocates the mask.
  std::vector<uint8_t> interior_pixels() const;
  // The same test in three kinds of pixel: 1 interior; 0 a boundary (the centre and a corner see
  // different objects or shadow states: a silhouette or a shadow edge); 2 a view's turn (one
  // surface and shadow state, but the cosines differ beyond the ratio). The renderer takes more
  // strata on a boundary (docs/rendering.md, "Edge pixels"). Traces and allocates as above.
  std::vector<uint8_t> pixel_kinds() const;

  const Scene& scene() const { return scene_; }

 private:
  struct Impl;
  const Scene& scene_;
  RenderOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace clothbake::render

// clothbake render: renders a scene with the evaluator (docs/rendering.md, docs/scene-format.md).
//
//   clothbake render SCENE.toml -o OUT.exr [--method M] [--spp N] [--edges jittered|centre]
//   [--time-budget S] [--threads N]
//                    [--seed S] [--tables auto|raw|compressed] [--exposure EV]
//                    [--sheen-convention published|converged] [--cache DIR] [--json]
//
// Writes OUT.exr (linear float RGB) and OUT.png (the scene's [render] exposure and tone map, sRGB)
// atomically (temporary names renamed on success). Objects with `fabric =` are baked into the
// cache first (scene_bake.hpp).
// Exit codes: 1 bad options, 2 a bad scene, missing file or unwritable output, 3 an invalid asset.
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/scene_load.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/progress.hpp"
#include "bake/reports/scene_bake.hpp"
#include "common/error.hpp"
#include "model/parameter_text.hpp"
#include "render/image_output.hpp"
#include "render/renderer.hpp"
#include "render/sample_limit.hpp"

namespace clothbake::cli {
namespace {

namespace fs = std::filesystem;

struct RenderCliOptions {
  std::string scene, output, method = "multiscale", cache, image_size;
  eval::TableChoice tables = eval::TableChoice::Auto;
  std::string sheen_convention = "published";
  std::string edges = "jittered";
  uint32_t spp = 2;
  double time_budget = 0;
  int threads = 0;
  uint64_t seed = 1;
  std::optional<double> exposure;
  bool json = false;
};

int run_render(const RenderCliOptions& o) {
  eval::Method method;
  if (!eval::parse_method(o.method.c_str(), &method))
    throw CLI::ValidationError("--method", "unknown method '" + o.method + "'");
  if (o.spp == 0) throw CLI::ValidationError("--spp", "must be at least 1");
  if (!(o.time_budget >= 0) || !(o.time_budget <= kMaxTimeBudgetSeconds))
    throw CLI::ValidationError("--time-budget", "must be a number of seconds in [0, 86400]");
  render::check_output_path(o.output);

  inputs::LoadedScene loaded = inputs::load_scene(o.scene);
  if (!o.image_size.empty()) {
    const std::array<int, 2> wh = parse_image_size(o.image_size);
    loaded.scene.camera.width = wh[0];
    loaded.scene.camera.height = wh[1];
  }
  render::check_render_samples(loaded.scene.camera.width, loaded.scene.camera.height, o.spp,
                               "--spp");
  if (o.exposure) loaded.scene.preview.exposure = *o.exposure;
  reports::bake_scene_fabrics(loaded, o.cache, /*quiet=*/o.json);
  std::unique_ptr<tbb::global_control> limit;
  if (o.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  std::size_t(o.threads));
  render::RenderOptions ro;
  ro.method = method;
  ro.spp = o.spp;
  ro.seed = o.seed;
  ro.time_budget = o.time_budget;
  ro.jitter_edges = o.edges == "jittered";
  ro.tables = o.tables;
  model::parse_sheen_convention(o.sheen_convention, ro.sheen_convention);  // checked by IsMember
  const render::Renderer renderer(loaded.scene, ro);
  pipeline::ProgressBar bar(!o.json && pipeline::ProgressBar::stderr_is_terminal());
  bar.begin(fmt::format("render {}x{} {} {} spp", loaded.scene.camera.width,
                        loaded.scene.camera.height, eval::method_name(method), o.spp));
  const render::RenderResult result = renderer.render([&](double f) { bar.update(f); });
  bar.finish();
  const render::OutputFiles files =
      render::write_render_images(o.output, result, loaded.scene.preview);
  const render::RenderStats& s = result.stats;
  if (o.json) {
    print_json({{"scene", o.scene},
                {"method", eval::method_name(method)},
                {"spp", o.spp},
                {"passes", s.passes},
                {"seed", o.seed},
                {"resolution", {result.width, result.height}},
                {"seconds", s.seconds},
                {"exr", files.exr},
                {"png", files.png},
                {"estimates", s.estimates},
                {"texel_evals", s.texel_evals},
                {"samples", s.samples},
                {"direct_footprints", s.direct},
                {"without_control_variate", s.without_control_variate},
                {"remainder_samples", s.remainder_samples},
                {"visibility_samples", s.visibility_samples},
                {"out_of_plan", s.out_of_plan},
                {"out_of_plan_brute_fallback", s.fallback_brute},
                {"out_of_plan_zero", s.fallback_zero},
                {"cloth_pixels", s.cloth_pixels},
                {"edge_pixels", s.edge_pixels},
                {"negative_pixels", s.negative_pixels},
                {"min_value", s.min_value},
                {"footprint_side_texels",
                 {std::sqrt(s.footprint_texels_min), std::sqrt(s.footprint_texels_max)}}});
    return 0;
  }
  std::printf("rendered %s: %dx%d, %s, %u spp x %u pass(es), %.3g s\n",
              terminal_safe(o.scene).c_str(), result.width, result.height,
              eval::method_name(method), o.spp, s.passes, s.seconds);
  // Footprints as sides (the square root of their areas), the unit of plan and eval.
  std::printf("  cloth pixels %llu, footprints %.3g to %.3g texels a side, %llu estimates\n",
              static_cast<unsigned long long>(s.cloth_pixels), std::sqrt(s.footprint_texels_min),
              std::sqrt(s.footprint_texels_max), static_cast<unsigned long long>(s.estimates));
  if (s.negative_pixels > 0)
    std::printf(
        "  %llu pixels with a negative channel in the EXR (least %.3g; black in the PNG): "
        "estimator noise around the exact value, fewer with more --spp\n",
        static_cast<unsigned long long>(s.negative_pixels), s.min_value);
  std::printf("  %s\n  %s\n", terminal_safe(files.exr).c_str(), terminal_safe(files.png).c_str());
  return 0;
}

const bool render_registered = register_command(
    {"render", "render a scene (TOML) with the multi-scale evaluator: EXR and a PNG preview",
     [](CLI::App& app) -> Action {
       auto o = std::make_shared<RenderCliOptions>();
       app.add_option("SCENE", o->scene, "scene description (.toml, docs/scene-format.md)")
           ->required();
       app.add_option("-o,--output", o->output, "output image (.exr); a .png preview beside it")
           ->required();
       app.add_option(
              "--method", o->method,
              "multiscale (default), multiscale-paper, brute or reference (docs/evaluator.md)")
           ->check(CLI::IsMember({"multiscale", "multiscale-paper", "brute", "reference"}));
       app.add_option("--spp", o->spp, "samples per pixel footprint and light (default 2)");
       app.add_option("--edges", o->edges,
                      "pixels on silhouettes, shadow edges and turns of the view: jittered "
                      "(path traced from at least 8 x 8 stratified camera rays, each evaluated at "
                      "its hit; default) or centre (the centre's footprint, as every other pixel; "
                      "docs/rendering.md)")
           ->check(CLI::IsMember({"jittered", "centre"}));
       app.add_option("--image-size", o->image_size,
                      "W,H: render at W x H pixels instead of the scene camera's resolution (the "
                      "vertical field of view is kept)");
       app.add_option("--time-budget", o->time_budget,
                      "seconds: repeat passes of --spp until spent (the image then depends on the "
                      "machine's speed)");
       add_threads_option(app, o->threads, "rendering threads (the image is identical for any N)");
       app.add_option("--seed", o->seed, "seed of every sample (default 1)");
       app.add_option("--exposure", o->exposure,
                      "stops: the PNG preview's exposure, instead of the scene's [render] "
                      "exposure (the EXR stays linear)")
           ->check(CLI::Range(-render::kMaxExposureStops, render::kMaxExposureStops));
       add_tables_option(app, o->tables);
       app.add_option("--sheen-convention", o->sheen_convention,
                      "sheen table: published (Zeltner et al.'s, as Cycles ships it; default) or "
                      "converged (docs/sheen.md)")
           ->check(CLI::IsMember({"published", "converged"}));
       app.add_option("--cache", o->cache,
                      "folder for assets baked from `fabric =` objects (default: $CLOTHBAKE_CACHE, "
                      "else ~/.cache/clothbake)");
       add_json_flag(app, o->json, "print the render's statistics as JSON on stdout");
       return [o] { return run_render(*o); };
     }});

}  // namespace
}  // namespace clothbake::cli

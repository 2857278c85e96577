// The `visibility` stage (paper Sec. 3.1, 4.2): the fabric's height map in, one ASG per
// texel with its fit error out (raycast/visibility.hpp,
// formats/reader/visibility_sections.hpp), plus the decoded lobes as the artifact
// "visibility/asg_params" (std::vector<model::AsgParams<float>>, texel order) for the visibility
// clustering. Settings: [bake] visibility_dirs. The per-texel fit errors (asg_fit_error, f32, 0.26
// MB at 256^2: information, no reader needs them) are written only when the raw data is kept
// (--keep-raw, or uncompressed bakes: the parallax stage's rule); the info record's mean and
// maximum fit error always are.
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "compress/compress_settings.hpp"
#include "fabric/fabric.hpp"
#include "raycast/raycast_sections.hpp"
#include "raycast/visibility.hpp"

namespace clothbake::stages {
namespace {

using namespace raycast;  // the algorithm library this stage drives

void run_visibility(pipeline::StageContext& ctx) {
  const Fabric& fabric = ctx.input<Fabric>("fabric");
  VisibilitySettings settings;
  settings.dirs = fabric.bake.visibility_dirs;
  // A scene plan may sample fewer light directions where every footprint averages the ASGs of
  // many texels (docs/scene-plans.md, "Visibility directions"); the clusters' mean-visibility
  // grid keeps the fabric's setting.
  if (ctx.has_input(kScenePlanArtifact)) {
    const int planned = ctx.input<PlannedBake>(kScenePlanArtifact).visibility_dirs;
    if (planned > 0) settings.dirs = planned;
  }
  VisibilitySamples samples =
      sample_visibility(fabric.maps, settings, [&](double f) { ctx.progress(0.7 * f); });
  VisibilityAsgs asgs =
      fit_visibility(samples, settings, [&](double f) { ctx.progress(0.7 + 0.28 * f); });
  nlohmann::json meta = {
      {"dirs", settings.dirs},
      {"direction_grid", "DirectionGrid{dirs, 0} bin centres (upper hemisphere of light)"},
      {"normal_offset_texels", settings.normal_offset_texels},
      {"asg", "G(w) = c [w.z > 0] exp(-lambda (w.x)^2 - mu (w.y)^2), model/asg.hpp"},
      {"mean_fit_error", asgs.mean_fit_error},
      {"max_fit_error", asgs.max_fit_error},
      {"fit_warning_rms", settings.fit_warn_rms},
      {"texels_above_warning", asgs.texels_above_warning},
      {"rays", samples.rays},
      {"segments", samples.segments},
      {"unresolved_rays", samples.unresolved_rays},
      {"max_sideways_tiles", samples.max_sideways_tiles},
      {"rings", samples.rings},
  };
  ctx.output("visibility/asg_params", decoded_lobes(asgs));
  const compress::CompressSettings form =
      ctx.has_input(kCompressSettingsArtifact)
          ? compress::resolve_compress_settings(
                fabric.bake, ctx.input<compress::CompressRequest>(kCompressSettingsArtifact))
          : compress::settings_from_bake(fabric.bake);
  const bool fit_error_section = form.keep_raw || !form.enabled;
  meta["fit_error_section"] = fit_error_section;
  ctx.output("section/visibility",
             visibility_sections(asgs, settings, settings.dirs, fit_error_section));
  ctx.progress(1.0);
  ctx.output("metadata/visibility", std::move(meta));
}

}  // namespace

pipeline::Stage visibility_stage() {
  pipeline::Stage s;
  s.name = "visibility";
  s.description = "per-texel visibility sampled by ray casting, fitted by one ASG (Sec. 3.1, 4.2)";
  s.inputs = {"fabric"};
  s.outputs = {"section/visibility", "metadata/visibility", "visibility/asg_params"};
  s.collects = {kCompressSettingsArtifact, kScenePlanArtifact};
  s.run = run_visibility;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

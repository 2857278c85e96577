// The `parallax` stage (paper Sec. 3.2, 5.2): the fabric's height map in, the parallax
// table, its per-direction SATs and their parameters out (raycast/parallax.hpp,
// formats/reader/parallax_sections.hpp). Settings: [bake] parallax_dirs and parallax_min_cos.
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "fabric/fabric.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"

namespace clothbake::stages {
namespace {

using namespace raycast;  // the algorithm library this stage drives

void run_parallax(pipeline::StageContext& ctx) {
  const Fabric& fabric = ctx.input<Fabric>("fabric");
  ParallaxSettings settings;
  settings.dirs = fabric.bake.parallax_dirs;
  settings.min_cos = fabric.bake.parallax_min_cos;
  ParallaxTable table =
      bake_parallax(fabric.maps, settings, [&](double f) { ctx.progress(0.95 * f); });
  const ParallaxStats stats = table.stats;
  nlohmann::json meta = {
      {"dirs", table.dirs},
      {"min_cos", table.min_cos},
      {"direction_grid", "DirectionGrid{dirs, min_cos} bin centres, bin (i, j) at j * dirs + i"},
      {"reference_height", table.reference_height},
      {"depth_scale", table.depth_scale},
      {"r", "r = -code * depth_scale (tile-side units, <= 0): z_hit - reference_height"},
      {"max_quantization_error", stats.max_quantization_error},
      {"max_offset_tiles", stats.max_sideways},
      {"rays", stats.rays},
      {"segments", stats.segments},
      {"recast_rays", stats.recast_rays},
      {"unresolved_rays", stats.unresolved_rays},
      {"rings", stats.rings},
  };
  ctx.output("section/parallax", parallax_sections(std::move(table)));
  ctx.progress(1.0);
  ctx.output("metadata/parallax", std::move(meta));
}

}  // namespace

pipeline::Stage parallax_stage() {
  pipeline::Stage s;
  s.name = "parallax";
  s.description = "parallax depth per texel and view direction, and its SATs (Sec. 3.2, 5.2)";
  s.inputs = {"fabric"};
  s.outputs = {"section/parallax", "metadata/parallax"};
  s.run = run_parallax;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

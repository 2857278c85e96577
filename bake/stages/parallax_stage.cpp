// The `parallax` stage (paper Sec. 3.2, 5.2): the fabric's height map in, the parallax
// table and their parameters out (raycast/parallax.hpp, formats/reader/parallax_sections.hpp).
// Settings: [bake] parallax_dirs, parallax_min_cos, parallax_max_error.
//
// Form (docs/compression.md, "Hierarchical parallax"): when compression is on (the default; the
// bake's compress request, artifact kCompressSettingsArtifact, or [bake] compress), the table is
// quantised per direction to meet [bake] parallax_max_error (RMS offset error, texels), each
// direction predicted from up to four others and entropy-coded (compress/parallax_hierarchy.hpp,
// section parallax_entropy), without SATs; a warning when even the finest steps miss the target.
// The raw codes and their SATs are written only with --keep-raw. `--no-compress` (or compress =
// false) writes the raw codes and SATs alone. A scene-planned bake (--scene) stores the kept
// directions (and those they are predicted from), the left-out ones as empty blocks (the table
// flagged planned; docs/scene-plans.md).
#include <algorithm>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "compress/parallax_codes.hpp"
#include "compress/parallax_entropy.hpp"
#include "compress/parallax_hierarchy.hpp"
#include "fabric/fabric.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/parallax_sections.hpp"
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
  const PlannedBake* plan =
      ctx.has_input(kScenePlanArtifact) ? &ctx.input<PlannedBake>(kScenePlanArtifact) : nullptr;
  if (plan) settings.keep = plan->view_bins;
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
  const compress::CompressSettings form =
      ctx.has_input(kCompressSettingsArtifact)
          ? compress::resolve_compress_settings(
                fabric.bake, ctx.input<compress::CompressRequest>(kCompressSettingsArtifact))
          : compress::settings_from_bake(fabric.bake);
  std::vector<formats::Section> sections;
  bool compressed = false;
  if (form.enabled) {
    const compress::ParallaxCodes raw{table.depth.data(), table.resolution,  table.dirs,
                                      table.min_cos,      table.depth_scale, table.reference_height,
                                      stats.max_sideways};
    const double max_error = plan != nullptr && plan->parallax_max_error > 0
                                 ? plan->parallax_max_error
                                 : fabric.bake.parallax_max_error;
    compressed = true;
    // Format 1.5: 16-bit codes with steps from the error target, each direction predicted from up
    // to four others and entropy-coded (compress/parallax_hierarchy.hpp). A scene-planned bake
    // stores the plan's view directions (closed under the references by the plan) with the same
    // codes as the full bake, the others as empty blocks.
    const compress::HierarchicalParallax coded =
        compress::hierarchical_parallax(raw, max_error, settings.keep);
    ctx.progress(0.99);
    if (coded.rms_offset_error > max_error)
      warn("parallax: the finest 16-bit codes reach an RMS offset error of " +
           std::to_string(coded.rms_offset_error) + " texels, above parallax_max_error " +
           std::to_string(max_error));
    sections = compress::hierarchical_parallax_sections(coded);
    nlohmann::json shifts = nlohmann::json::array();
    for (const auto& [sx, sy] : coded.candidates)
      shifts.push_back({sx, sy});
    const bool timings = ctx.options().record_timings;
    meta["compressed"] = {{"max_error", max_error},
                          {"section", "parallax_entropy"},
                          {"form", "hierarchical"},
                          {"bits", 16},
                          {"max_code", coded.max_code},
                          {"quantisation_rounds", coded.quantisation_rounds},
                          {"rms_offset_error_texels", coded.rms_offset_error},
                          {"max_offset_error_texels", coded.max_offset_error},
                          {"share_above_quarter_texel", coded.share_above_quarter},
                          {"max_depth_error", coded.max_depth_error},
                          {"compressed_bytes", coded.payload_bytes()},
                          {"entropy_coded_bytes", coded.stream.size()},
                          {"raw_bytes", uint64_t(table.depth.size()) * 6},
                          {"shift_candidates", shifts},
                          {"shifted_blocks", coded.shifted_blocks},
                          {"groups", coded.groups},
                          {"seconds", timings ? coded.seconds_quantise : 0.0},
                          {"entropy_seconds", timings ? coded.seconds_code : 0.0}};
    meta["keep_raw"] = form.keep_raw;
    if (!settings.keep.empty())
      meta["planned"] = {{"view_bins_kept", compress::kept_direction_count(settings.keep)},
                         {"view_bins_total", settings.keep.size()}};
  }
  if (!settings.keep.empty() && (!compressed || form.keep_raw))
    throw_internal_error("parallax: a scene-planned bake writes the compressed form only");
  if (!compressed || form.keep_raw)
    for (auto& s : parallax_sections(std::move(table)))
      sections.push_back(std::move(s));
  ctx.output("section/parallax", std::move(sections));
  ctx.progress(1.0);
  ctx.output("metadata/parallax", std::move(meta));
}

}  // namespace

pipeline::Stage parallax_stage() {
  pipeline::Stage s;
  s.name = "parallax";
  s.description =
      "parallax depth per texel and view direction, compressed or as codes and SATs (Sec. 3.2, "
      "5.2)";
  s.inputs = {"fabric"};
  s.outputs = {"section/parallax", "metadata/parallax"};
  s.collects = {kCompressSettingsArtifact, kScenePlanArtifact};
  s.run = run_parallax;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

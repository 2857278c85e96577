// The `parallax` stage (paper Sec. 3.2, 5.2): the fabric's height map in, the parallax
// table and their parameters out (raycast/parallax.hpp, formats/reader/parallax_sections.hpp).
// Settings: [bake] parallax_dirs, parallax_min_cos, parallax_max_error.
//
// Form (docs/compression.md, "Compressed parallax"): when compression is on (the default; the
// bake's compress request, artifact kCompressSettingsArtifact, or [bake] compress), the table is
// requantised to 8 bits per direction (compress/parallax_codes.hpp) if that meets [bake]
// parallax_max_error (RMS offset error, texels; otherwise a warning and 16-bit codes, still
// without SATs), and the raw codes and their SATs are written only with --keep-raw. `--no-compress`
// (or compress = false) writes the raw codes and SATs alone, exactly as format 1.0 did.
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "compress/compress_settings.hpp"
#include "compress/parallax_codes.hpp"
#include "fabric/fabric.hpp"
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
    const double max_error = fabric.bake.parallax_max_error;
    compress::QuantisedParallax packed = compress::quantise_parallax(raw, max_error);
    ctx.progress(0.99);
    compressed = true;
    if (packed.bits == 16)
      warn("parallax: 8-bit codes would reach an RMS offset error of " +
           std::to_string(packed.rms_offset_error_8bit) + " texels, above parallax_max_error " +
           std::to_string(max_error) +
           ": the compressed table keeps 16-bit codes (2 bytes per "
           "texel and direction)");
    meta["compressed"] = {{"max_error", max_error},
                          {"bits", packed.bits},
                          {"rms_offset_error_8bit_texels", packed.rms_offset_error_8bit},
                          {"rms_offset_error_texels", packed.rms_offset_error},
                          {"max_offset_error_texels", packed.max_offset_error},
                          {"share_above_quarter_texel", packed.share_above_quarter},
                          {"max_depth_error", packed.max_depth_error},
                          {"compressed_bytes", packed.payload_bytes()},
                          {"raw_bytes", uint64_t(table.depth.size()) * 6},
                          {"seconds", ctx.options().record_timings ? packed.seconds : 0.0}};
    meta["keep_raw"] = form.keep_raw;
    sections = compress::compressed_parallax_sections(packed);
  }
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
  s.collects = {kCompressSettingsArtifact};
  s.run = run_parallax;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

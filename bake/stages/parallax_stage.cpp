// The `parallax` stage (paper Sec. 3.2, 5.2): the fabric's height map in, the parallax
// table and their parameters out (raycast/parallax.hpp, formats/reader/parallax_sections.hpp).
// Settings: [bake] parallax_dirs, parallax_min_cos, parallax_max_error.
//
// Form (docs/compression.md, "Compressed parallax"): when compression is on (the default; the
// bake's compress request, artifact kCompressSettingsArtifact, or [bake] compress), the table is
// requantised to 8 bits per direction (compress/parallax_codes.hpp) if that meets [bake]
// parallax_max_error (RMS offset error, texels) and entropy-coded (compress/parallax_entropy.hpp,
// section parallax_entropy, format 1.2); otherwise a warning and 16-bit codes (parallax_compressed,
// format 1.1), still without SATs. The raw codes and their SATs are written only with --keep-raw.
// `--no-compress` (or compress = false) writes the raw codes and SATs alone, exactly as format 1.0
// did. A scene-planned bake (--scene) entropy-codes the kept directions' 8-bit codes, the left-out
// ones as empty blocks (parallax_entropy flagged planned, format 1.3), or with 16-bit codes writes
// the kept directions' codes plainly (parallax_planned, format 1.2; docs/scene-plans.md).
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
#include "fabric/fabric.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"

namespace clothbake::stages {
namespace {

using namespace raycast;  // the algorithm library this stage drives

// The planned form (format 1.2): the compressed sections restricted to the kept directions, as
// ParallaxPlanned. The steps (instance 1) and codes (instance 2) keep the slices of the kept bins
// in bin order; the info record's RMS offset error, measured over every bin, is rescaled to the
// kept ones (the left-out bins cast no rays: code 0, error exactly 0).
std::vector<formats::Section> planned_parallax_sections(std::vector<formats::Section> packed,
                                                        const std::vector<uint8_t>& keep) {
  const std::size_t kept = compress::kept_direction_count(keep);
  for (formats::Section& s : packed) {
    s.type = reader::SectionType::ParallaxPlanned;
    if (s.instance == reader::kCompressedParallaxInfoInstance) {
      reader::CompressedParallaxInfoRecord info;
      std::memcpy(&info, s.payload.data(), sizeof info);
      info.rms_offset_error *= std::sqrt(double(keep.size()) / double(kept));
      std::memcpy(s.payload.data(), &info, sizeof info);
      continue;
    }
    if (s.dims.empty() || s.dims[0] != keep.size())
      throw_internal_error("planned parallax: a section without one slice per direction");
    const std::size_t slice = s.payload.size() / keep.size();
    std::vector<std::byte> out;
    out.reserve(slice * kept);
    for (std::size_t d = 0; d < keep.size(); ++d)
      if (keep[d])
        out.insert(out.end(), s.payload.begin() + std::ptrdiff_t(d * slice),
                   s.payload.begin() + std::ptrdiff_t((d + 1) * slice));
    s.payload = std::move(out);
    s.dims[0] = uint32_t(kept);
  }
  return packed;
}

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
    if (!settings.keep.empty() && packed.bits == 8) {
      // Scene-planned, 8-bit (format 1.3): entropy-coded like the full asset, the left-out
      // directions as empty blocks, flagged planned (coverage: bin_map instance 1).
      const compress::EntropyParallax coded =
          compress::entropy_code_parallax(packed, settings.keep);
      sections = compress::planned_entropy_parallax_sections(packed, coded, settings.keep);
      const std::size_t kept = compress::kept_direction_count(settings.keep);
      meta["compressed"]["section"] = "parallax_entropy";
      meta["compressed"]["entropy_coded_bytes"] = coded.stream.size();
      meta["compressed"]["shifted_blocks"] = coded.shifted_blocks;
      meta["compressed"]["entropy_seconds"] = ctx.options().record_timings ? coded.seconds : 0.0;
      meta["planned"] = {{"view_bins_kept", kept}, {"view_bins_total", settings.keep.size()}};
    } else if (!settings.keep.empty()) {  // scene-planned, 16-bit: the kept directions' codes
      sections =
          planned_parallax_sections(compress::compressed_parallax_sections(packed), settings.keep);
      meta["compressed"]["section"] = "parallax_planned";
      meta["planned"] = {{"view_bins_kept", sections.back().dims[0]},
                         {"view_bins_total", settings.keep.size()}};
    } else if (packed.bits == 8) {  // format 1.2: the 8-bit codes entropy-coded per direction
      const compress::EntropyParallax coded = compress::entropy_code_parallax(packed);
      sections = compress::entropy_parallax_sections(packed, coded);
      nlohmann::json shifts = nlohmann::json::array();
      for (const auto& [sx, sy] : coded.candidates)
        shifts.push_back({sx, sy});
      meta["compressed"]["section"] = "parallax_entropy";
      meta["compressed"]["entropy_coded_bytes"] = coded.stream.size();
      meta["compressed"]["shift_candidates"] = shifts;
      meta["compressed"]["shifted_blocks"] = coded.shifted_blocks;
      meta["compressed"]["entropy_seconds"] = ctx.options().record_timings ? coded.seconds : 0.0;
    } else {
      meta["compressed"]["section"] = "parallax_compressed";
      sections = compress::compressed_parallax_sections(packed);
    }
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

// The `compress` stage (paper Sec. 4.4): the raw Integral-Radiance table sections of the
// `tables` stage and the label map of the `cluster` stage (artifact "clusters") in, C-PCA
// compressed sections out (compress/compressed_set.hpp), one kind after the other, with the
// fabric's [bake] settings overridden by the bake command's request (artifact
// kCompressSettingsArtifact, a CompressRequest). When the tables stage streamed (no raw SATs were
// built), the values come from its fills (kStreamedTablesArtifact) instead of the raw sections.
//
// Unless the raw tables are kept, the stage also publishes "supersedes/compress" =
// {"section/tables"} when it produced compressed tables: the write stage then leaves the raw
// tables out of the asset (docs/pipeline.md, "Superseded sections"; docs/compression.md, "Bake").
#include <chrono>
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "bake/stages/table_streaming.hpp"
#include "cluster/visibility_clusters.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "compress/compressed_set.hpp"
#include "compress/cpca.hpp"
#include "compress/directional_texels.hpp"
#include "fabric/fabric.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::stages {
namespace {

using namespace compress;  // the algorithm library this stage drives

void run_compress(pipeline::StageContext& ctx) {
  const CompressSettings settings = compress_settings(ctx);
  nlohmann::json meta;
  meta["enabled"] = settings.enabled;
  meta["keep_raw"] = settings.keep_raw || !settings.enabled;
  meta["settings"] = settings.describe();
  std::vector<formats::Section> out;
  if (!settings.enabled) {
    ctx.output("section/compress", std::move(out));
    ctx.output("metadata/compress", meta);
    ctx.output(kCompressSupersedesArtifact, std::vector<std::string>{});
    return;
  }
  const auto& raw = ctx.input<std::vector<formats::Section>>("section/tables");
  const auto& labels = ctx.input<cluster::VisibilityClusters>("clusters").labels;
  const StreamedTablesArtifact& streamed =
      ctx.input<StreamedTablesArtifact>(kStreamedTablesArtifact);
  // The streaming fill of a kind, or null (then the raw sections are read).
  auto fill_of = [&](reader::RadianceTableKind kind) -> const tables::QuantisedRadianceFill* {
    if (!streamed) return nullptr;
    for (const auto& fill : streamed->fills)
      if (fill.header().kind() == kind) return &fill;
    return nullptr;
  };
  // A scene-driven bake: only the kept half-vector bins, no gap kind without transmission.
  const PlannedBake* plan =
      ctx.has_input(kScenePlanArtifact) ? &ctx.input<PlannedBake>(kScenePlanArtifact) : nullptr;
  nlohmann::json kinds = nlohmann::json::array();
  const reader::RadianceTableKind order[] = {reader::RadianceTableKind::Specular,
                                             reader::RadianceTableKind::Gap};
  for (int i = 0; i < 2; ++i) {
    const tables::QuantisedRadianceFill* fill = fill_of(order[i]);
    const auto view = tables::find_radiance_sections(raw, order[i]);
    if (fill == nullptr && !view.present()) continue;
    const bool specular = order[i] == reader::RadianceTableKind::Specular;
    if (plan && !specular && !plan->transmission) continue;  // the gap kind: transmission only
    const bool reduce = plan && specular && !plan->half_vector_bins.empty();
    if (reduce && !fill)
      throw_internal_error("compress: a scene-planned bake needs the streamed tables");
    const auto start = std::chrono::steady_clock::now();
    // Bit-identical either way (compress/directional_texels.hpp).
    const DirectionalTexels data =
        fill ? directional_texels(*fill, reduce ? std::span<const uint8_t>(plan->half_vector_bins)
                                                : std::span<const uint8_t>())
             : directional_texels(view, labels);
    ctx.progress(0.5 * i + 0.1);
    CompressionStats stats;
    CompressedTableSet set = compress_tables(data, settings.cpca(), &stats);
    if (reduce) {  // bins of bin_map 0 only; part 4 stores their columns alone
      set.info.flags |= reader::kCompressedPlannedFlag;
      set.covered = plan->half_vector_bins;
      stats.compressed_bytes = set.payload_bytes();
    }
    for (auto& s : compressed_sections(set))
      out.push_back(std::move(s));
    ctx.progress(0.5 * (i + 1));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!settings.fixed && stats.error > settings.max_error * 1.0001)
      warn("compress: the " + std::string(reader::radiance_kind_name(order[i])) +
           " tables reach a relative RMS error of " + std::to_string(stats.error) +
           " at the rank cap " + std::to_string(settings.rank) + ", above the target " +
           std::to_string(settings.max_error));
    kinds.push_back({{"kind", reader::radiance_kind_name(order[i])},
                     {"cells", stats.cells},
                     {"images", stats.images},
                     {"min_rank", stats.min_rank},
                     {"max_rank", stats.max_rank},
                     {"relative_rms_error", stats.error},
                     {"cpca_relative_rms_error", stats.cpca_error},
                     {"max_abs_error", stats.max_abs_error},
                     {"raw_float_bytes", stats.raw_float_bytes},
                     {"compressed_bytes", stats.compressed_bytes},
                     {"ratio", stats.ratio()},
                     {"seconds", ctx.options().record_timings ? seconds : 0.0}});
  }
  meta["kinds"] = kinds;
  meta["mode"] = settings.fixed ? "fixed" : "target";
  meta["clusters"] = settings.clusters;
  meta["rank"] = settings.rank;
  if (!settings.fixed) meta["max_error"] = settings.max_error;
  // The raw tables are superseded only when there is something to replace them with.
  const bool drop_raw = !settings.keep_raw && !out.empty();
  meta["keep_raw"] = !drop_raw;
  ctx.output("section/compress", std::move(out));
  ctx.output("metadata/compress", meta);
  ctx.output(kCompressSupersedesArtifact,
             drop_raw ? std::vector<std::string>{"section/tables"} : std::vector<std::string>{});
}

}  // namespace

pipeline::Stage compress_stage() {
  pipeline::Stage s;
  s.name = "compress";
  s.description = "C-PCA compression of the Integral-Radiance tables (paper Sec. 4.4)";
  s.inputs = {"fabric", "section/tables", "clusters", kStreamedTablesArtifact};
  s.outputs = {"section/compress", "metadata/compress", kCompressSupersedesArtifact};
  s.collects = {kCompressSettingsArtifact, kScenePlanArtifact};
  s.run = run_compress;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

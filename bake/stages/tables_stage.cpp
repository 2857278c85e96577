// The `tables` stage (paper Sec. 4.3): the raw Integral-Radiance tables of every lobe the
// fabric needs (specular always; the gap table when some texel has I(x) < 1), per visibility
// cluster and half-vector bin, as exact fixed-point SATs (sections radiance_tables; layout in
// formats/reader/radiance_layout.hpp). Settings: [bake] radiance_dirs. Warns when the bins cannot
// resolve the narrowest lobe (2-sigma rule) and says which radiance_dirs would.
//
// When the bake writes only compressed tables, the raw SATs are never built: the stage publishes
// the same metadata, an empty "section/tables" and the streaming fills (kStreamedTablesArtifact),
// from which the compress stage computes the values bin by bin (docs/pipeline.md, "Streaming the
// tables into the compression").
#include <algorithm>
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "bake/stages/table_streaming.hpp"
#include "cluster/visibility_clusters.hpp"
#include "fabric/fabric.hpp"
#include "tables/fixed_point_sat.hpp"
#include "tables/half_vector_bins.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::stages {
namespace {

using namespace tables;  // the algorithm library this stage drives

// True when nothing of this bake reads the raw tables: the compress stage runs, compresses and
// does not keep them (no --keep-raw, no --no-compress). The raw SATs are then never built.
bool stream_into_compression(const pipeline::StageContext& ctx) {
  const auto& order = ctx.stage_order();
  if (std::find(order.begin(), order.end(), "compress") == order.end()) return false;
  const compress::CompressSettings settings = compress_settings(ctx);
  return settings.enabled && !settings.keep_raw;
}

nlohmann::json kind_summary(const RadianceTableSet& set, std::size_t sat_bytes) {
  return {{"kind", reader::radiance_kind_name(set.kind())},
          {"bins_per_side", set.info.bins_per_side},
          {"stored_clusters", set.clusters},
          {"element_bits", set.info.element_bits},
          {"sat_bytes", sat_bytes}};
}

void run_tables(pipeline::StageContext& ctx) {
  const Fabric& fabric = ctx.input<Fabric>("fabric");
  const auto& clusters = ctx.input<cluster::VisibilityClusters>("clusters");
  const RadianceOptions options = radiance_options(fabric);
  RadianceBuildReport report;
  nlohmann::json kinds = nlohmann::json::array();
  std::vector<formats::Section> sections;
  uint64_t bytes = 0;
  StreamedTablesArtifact streamed;
  if (stream_into_compression(ctx)) {
    // The same records and report as the raw build; the values are produced by the compress
    // stage, bin by bin, from these fills.
    std::vector<double> roughness;
    for (const auto& yarn : fabric.yarns)
      roughness.push_back(yarn.roughness);
    streamed = make_streamed_tables(fabric.maps.resolution, fabric.maps.tangent, fabric.maps.gap,
                                    fabric.maps.yarn_id, std::move(roughness), clusters.labels,
                                    clusters.clusters, options, &report);
    for (const auto& fill : streamed->fills) {
      bytes += fill.raw_sat_bytes();
      kinds.push_back(kind_summary(fill.header(), fill.raw_sat_bytes()));
    }
  } else {
    auto inputs = radiance_inputs(fabric, clusters.labels, clusters.clusters);
    std::vector<RadianceTableSet> sets = build_radiance_tables(inputs.view, options, &report);
    for (auto& set : sets) {
      bytes += set.sat.size();
      kinds.push_back(kind_summary(set, set.sat.size()));
      for (auto& s : radiance_sections(std::move(set)))
        sections.push_back(std::move(s));
    }
  }
  ctx.progress(0.95);
  // The wall time of the fill is not stored in the asset (it would make the bytes differ run to
  // run); the bake report has every stage's time.
  nlohmann::json meta = {
      {"radiance_dirs", options.bins_per_side},
      {"direction_grid", "DirectionGrid{radiance_dirs, 0}: folded half vectors, bin averages"},
      {"samples_per_bin_side", report.samples_per_side},
      {"min_roughness", report.min_roughness},
      {"radiance_dirs_needed", report.bins_needed},
      {"resolved", report.resolved},
      {"storage", "exact fixed-point SATs, u32 or u64 per precision target"},
      {"precision_target", options.max_relative_error},
      {"relative_error_bound", report.relative_error_bound},
      {"element_bits", report.element_bits},
      {"d_evaluations", report.d_evaluations},
      {"sat_bytes", bytes},
      {"tables", kinds},
  };
  ctx.output("section/tables", std::move(sections));
  ctx.output("metadata/tables", std::move(meta));
  ctx.output(kStreamedTablesArtifact, std::move(streamed));
  ctx.progress(1.0);
}

}  // namespace

pipeline::Stage tables_stage() {
  pipeline::Stage s;
  s.name = "tables";
  s.description = "Integral-Radiance tables per lobe, cluster and half-vector bin (Sec. 4.3)";
  s.inputs = {"fabric", "clusters"};
  s.outputs = {"section/tables", "metadata/tables", kStreamedTablesArtifact};
  // Reads the compression request to decide whether the raw SATs are needed at all.
  s.collects = {kCompressSettingsArtifact};
  s.run = run_tables;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

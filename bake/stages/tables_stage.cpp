// The `tables` stage (paper Sec. 4.3): the raw Integral-Radiance tables of every lobe the
// fabric needs (specular always; the gap table when some texel has I(x) < 1), per visibility
// cluster and half-vector bin, as exact fixed-point SATs (sections radiance_tables; layout in
// formats/reader/radiance_layout.hpp). Settings: [bake] radiance_dirs. Warns when the bins cannot
// resolve the narrowest lobe (2-sigma rule) and says which radiance_dirs would.
#include <chrono>
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "cluster/visibility_clusters.hpp"
#include "fabric/fabric.hpp"
#include "tables/fixed_point_sat.hpp"
#include "tables/half_vector_bins.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::stages {
namespace {

using namespace tables;  // the algorithm library this stage drives

void run_tables(pipeline::StageContext& ctx) {
  const Fabric& fabric = ctx.input<Fabric>("fabric");
  const auto& clusters = ctx.input<cluster::VisibilityClusters>("clusters");
  auto inputs = radiance_inputs(fabric, clusters.labels, clusters.clusters);
  RadianceOptions options;
  options.bins_per_side = fabric.bake.radiance_dirs;
  RadianceBuildReport report;
  const auto start = std::chrono::steady_clock::now();
  std::vector<RadianceTableSet> sets = build_radiance_tables(inputs.view, options, &report);
  const double fill_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ctx.progress(0.95);
  nlohmann::json kinds = nlohmann::json::array();
  std::vector<formats::Section> sections;
  uint64_t bytes = 0;
  for (auto& set : sets) {
    bytes += set.sat.size();
    kinds.push_back({{"kind", reader::radiance_kind_name(set.kind())},
                     {"bins_per_side", set.info.bins_per_side},
                     {"stored_clusters", set.clusters},
                     {"element_bits", set.info.element_bits},
                     {"sat_bytes", set.sat.size()}});
    for (auto& s : radiance_sections(std::move(set)))
      sections.push_back(std::move(s));
  }
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
  // Wall time of the fill is not stored in the asset (it would make the bytes differ run to
  // run); the bake report has every stage's time.
  (void)fill_seconds;
  ctx.output("section/tables", std::move(sections));
  ctx.output("metadata/tables", std::move(meta));
  ctx.progress(1.0);
}

}  // namespace

pipeline::Stage tables_stage() {
  pipeline::Stage s;
  s.name = "tables";
  s.description = "Integral-Radiance tables per lobe, cluster and half-vector bin (Sec. 4.3)";
  s.inputs = {"fabric", "clusters"};
  s.outputs = {"section/tables", "metadata/tables"};
  s.run = run_tables;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

// A fabric's specular texels with the bake's visibility clusters (compression_data.hpp).
#include "bake/reports/compression_data.hpp"

#include <utility>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/driver.hpp"
#include "bake/pipeline/stage.hpp"
#include "bake/stages/stages.hpp"
#include "cluster/visibility_clusters.hpp"

namespace clothbake::reports {
namespace {

// Visibility labels of `fabric`: the bake's own visibility and cluster stages (without the
// always-run fabric records and writer, which need an output).
std::vector<uint8_t> visibility_labels(const Fabric& fabric, int* clusters, std::string* source) {
  std::vector<pipeline::Stage> list;
  for (auto& s : stages::bake_stages())
    if (!s.always) list.push_back(std::move(s));
  pipeline::Artifacts seeded;
  seeded.put("fabric", fabric);
  pipeline::RunOptions run;
  pipeline::RunResult result = pipeline::run_pipeline({"cluster"}, std::move(seeded), run, list);
  const auto& c = result.artifacts.get<cluster::VisibilityClusters>("clusters");
  *clusters = c.clusters;
  *source = "visibility clusters (bake stages)";
  return c.labels;
}

}  // namespace

std::unique_ptr<CompressionData> load_compression_data(const std::string& path,
                                                       std::optional<int> resolution) {
  auto k = std::make_unique<CompressionData>();
  LoadOptions lo;
  lo.resolution = resolution;
  k->fabric = load_fabric_description(path, lo).fabric;
  k->labels = visibility_labels(k->fabric, &k->clusters, &k->label_source);
  k->inputs = tables::radiance_inputs(k->fabric, k->labels, k->clusters);
  k->data = compress::directional_texels(reader::RadianceTableKind::Specular, k->inputs.view,
                                         k->fabric.bake.radiance_dirs);
  return k;
}

}  // namespace clothbake::reports

// The `cluster` stage (paper Sec. 4.2): K-means on the per-texel visibility ASGs of the
// `visibility` stage -> label map and per-cluster mean visibility (sections cluster_labels and
// cluster_mean_visibility), plus the artifact "clusters" (cluster::VisibilityClusters) for the
// tables stage. Settings: [bake] clusters, seed, visibility_dirs (the mean-visibility grid).
#include <nlohmann/json.hpp>

#include "bake/stages/cache_support.hpp"
#include "bake/stages/stages.hpp"
#include "cluster/cluster_sections.hpp"
#include "cluster/visibility_clusters.hpp"
#include "fabric/fabric.hpp"
#include "model/asg.hpp"

namespace clothbake::stages {
namespace {

using namespace cluster;  // the algorithm library this stage drives

void run_cluster(pipeline::StageContext& ctx) {
  const Fabric& fabric = ctx.input<Fabric>("fabric");
  const auto& lobes = ctx.input<std::vector<model::AsgParams<float>>>("visibility/asg_params");
  VisibilityClusterOptions options;
  options.clusters = fabric.bake.clusters;
  options.seed = fabric.bake.seed;
  options.visibility_dirs = fabric.bake.visibility_dirs;
  VisibilityClusters clusters = cluster_visibility(fabric.maps.resolution, lobes, options);
  ctx.progress(0.9);
  ctx.output("section/clusters", cluster_sections(clusters));
  ctx.output("metadata/clusters", cluster_metadata(clusters, options));
  ctx.output("clusters", std::move(clusters));
  ctx.progress(1.0);
}

}  // namespace

pipeline::Stage cluster_stage() {
  pipeline::Stage s;
  s.name = "cluster";
  s.description =
      "visibility clusters: K-means on the ASG lobes, label map, mean visibility (Sec. 4.2)";
  s.inputs = {"fabric", "visibility/asg_params"};
  s.outputs = {"clusters", "section/clusters", "metadata/clusters"};
  s.run = run_cluster;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

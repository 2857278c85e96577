// The `cluster` stage (paper Sec. 4.2): K-means on the per-texel visibility ASGs of the
// `visibility` stage -> label map and per-cluster mean visibility (sections cluster_labels and
// cluster_mean_visibility), plus the artifact "clusters" (cluster::VisibilityClusters) for the
// tables stage, and the clusters' visibility basis (section cluster_visibility_basis,
// cluster/visibility_basis.hpp). Settings: [bake] clusters, clusters_by_yarn (split by the yarn id
// map), seed, visibility_dirs (the mean-visibility grid and the basis' bins), visibility_rank.
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
  if (fabric.bake.clusters_by_yarn) options.split_by = fabric.maps.yarn_id;
  VisibilityClusters clusters = cluster_visibility(fabric.maps.resolution, lobes, options);
  ctx.progress(0.6);
  const VisibilityBasis basis =
      fit_visibility_basis(fabric.maps.resolution, lobes, clusters.labels, clusters.clusters,
                           fabric.bake.visibility_dirs, fabric.bake.visibility_rank);
  ctx.progress(0.9);
  std::vector<formats::Section> sections = cluster_sections(clusters);
  for (formats::Section& s : visibility_basis_sections(basis))
    sections.push_back(std::move(s));
  ctx.output("section/clusters", std::move(sections));
  nlohmann::json meta = cluster_metadata(clusters, options);
  meta["clusters_by_yarn"] = fabric.bake.clusters_by_yarn;
  meta["visibility_rank"] = basis.rank;
  meta["visibility_basis_explained_fraction"] = basis.explained_fraction;
  ctx.output("metadata/clusters", std::move(meta));
  ctx.output("clusters", std::move(clusters));
  ctx.progress(1.0);
}

}  // namespace

pipeline::Stage cluster_stage() {
  pipeline::Stage s;
  s.name = "cluster";
  s.description =
      "visibility clusters: K-means on the ASG lobes split by yarn, label map, mean visibility "
      "(Sec. 4.2), per-cluster visibility basis";
  s.inputs = {"fabric", "visibility/asg_params"};
  s.outputs = {"clusters", "section/clusters", "metadata/clusters"};
  s.run = run_cluster;
  s.key_view = fabric_without_colours_view;  // albedos do not change its outputs
  return s;
}

}  // namespace clothbake::stages

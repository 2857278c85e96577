// Asset sections of the visibility clusters: the label map and the per-cluster mean visibility
// (layout: formats/reader/cluster_sections.hpp, docs/tables.md).
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "cluster/visibility_clusters.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::cluster {

// ClusterLabels u8 {N, N} and ClusterMeanVisibility f32 {C, n, n}, both instance 0, version 1.
// Throws Error(Internal) if `clusters` is inconsistent.
std::vector<formats::Section> cluster_sections(const VisibilityClusters& clusters);

// The clustering's parameters and per-cluster statistics (texels, inertia, variance explained),
// for the asset metadata and the bake report. Deterministic.
nlohmann::json cluster_metadata(const VisibilityClusters& clusters,
                                const VisibilityClusterOptions& options);

}  // namespace clothbake::cluster

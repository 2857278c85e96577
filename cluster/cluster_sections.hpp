// Asset sections of the visibility clusters: the label map and the per-cluster mean visibility
// (layout: formats/reader/cluster_sections.hpp, docs/tables.md).
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "cluster/visibility_basis.hpp"
#include "cluster/visibility_clusters.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::cluster {

// ClusterLabels u8 {N, N} and ClusterMeanVisibility f32 {C, n, n}, both instance 0, version 1.
// Throws Error(Internal) if `clusters` is inconsistent.
std::vector<formats::Section> cluster_sections(const VisibilityClusters& clusters);

// ClusterVisibilityBasis, version 1: instance 0 f32 {C, M + 1, n, n} (the components), instance 1
// f32 {N, N, M} (the per-texel coefficients; only when M > 0). Throws Error(Internal) if `basis`
// is inconsistent.
std::vector<formats::Section> visibility_basis_sections(const VisibilityBasis& basis);

// The clustering's parameters and per-cluster statistics (texels, inertia, variance explained),
// for the asset metadata and the bake report. Deterministic.
nlohmann::json cluster_metadata(const VisibilityClusters& clusters,
                                const VisibilityClusterOptions& options);

}  // namespace clothbake::cluster

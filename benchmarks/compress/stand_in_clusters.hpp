// Stand-in visibility clusters for the compression studies: k-means (8 clusters, default seed) on
// each texel's fibre tangent folded to one half-space and its yarn id. Cheaper than the bake's
// visibility and cluster stages and close enough to them for choosing a layout
// (docs/compression.md).
#pragma once

#include <cstdint>
#include <vector>

#include "cluster/kmeans.hpp"
#include "fabric/fabric.hpp"

namespace clothbake::studies {

struct StandInClusters {
  std::vector<uint8_t> labels;  // per texel, row-major
  int clusters = 0;
};

// The labels of `maps` (N x N texels). Deterministic.
inline StandInClusters stand_in_clusters(const FabricMaps& maps) {
  const std::size_t texels = maps.texel_count();
  std::vector<float> features(texels * 4);
  for (std::size_t t = 0; t < texels; ++t) {
    const Vec3f& tangent = maps.tangent[t];
    const float side = tangent[0] + tangent[1] < 0 ? -1.f : 1.f;  // t and -t are one fibre
    features[t * 4 + 0] = side * tangent[0];
    features[t * 4 + 1] = side * tangent[1];
    features[t * 4 + 2] = side * tangent[2];
    features[t * 4 + 3] = maps.yarn_id[t];
  }
  cluster::KMeansOptions options;
  options.clusters = 8;
  const auto result = cluster::kmeans({features.data(), texels, 4}, options);
  StandInClusters out;
  out.clusters = result.clusters;
  out.labels.resize(texels);
  for (std::size_t t = 0; t < texels; ++t)
    out.labels[t] = uint8_t(result.labels[t]);
  return out;
}

}  // namespace clothbake::studies

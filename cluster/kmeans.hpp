// Deterministic K-means on vectors of any dimension: the visibility clustering of paper Sec. 4.2
// (ASG parameter vectors, cluster/asg_embedding.hpp) and the clustering step of the C-PCA
// compression of Sec. 4.4 (compress/).
//
// Algorithm: k-means++ seeding (Arthur and Vassilvitskii 2007) from a fixed seed, then Lloyd
// iterations (assign every point to its nearest centre, move every centre to the mean of its
// points) until no label changes or the iteration budget is spent. A cluster that becomes empty is
// repaired by moving into it the point farthest from its own centre (taken from a cluster with at
// least two points), the standard fix that also lowers the inertia.
//
// Determinism: the result depends only on the points, the options and the seed, never on the
// thread count. Points are processed in fixed blocks of kBlockPoints; every parallel loop writes
// disjoint outputs, every sum is formed per block in point order and the block partials are added
// in block order; ties in the nearest-centre search go to the lower centre index. The seeding
// RNG is SplitMix64 (model/splitmix64.hpp), specified bit for bit.
//
// Nearest-centre search: brute force over the centres in double precision (ties to the lower
// index). A FLANN kd-tree over the centres was measured against it (docs/tables.md, "Nearest-centre
// search"): it only won for 3-dimensional points with 256 or more centres, a case clothbake never
// has (ASG embeddings have 11 dimensions and 8 centres, C-PCA vectors thousands of dimensions and a
// few centres), so it was removed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace clothbake::cluster {

// Points processed per block (the unit of parallel work and of the fixed-order reductions).
inline constexpr std::size_t kBlockPoints = 1024;

// n points of dimension d, row-major (point i at data[i * dim]). Not owned.
struct PointSet {
  const float* data = nullptr;
  std::size_t count = 0;
  std::size_t dim = 0;
  const float* point(std::size_t i) const { return data + i * dim; }
};

struct KMeansOptions {
  int clusters = 8;          // requested k >= 1
  int max_iterations = 100;  // Lloyd iterations after seeding, >= 1
  uint64_t seed = 1;         // k-means++ seed
  // Warm start: clusters x dim centres (row-major) used instead of k-means++ when not empty (e.g.
  // C-PCA reclustering from the previous iteration's clusters). Not owned.
  const double* initial_centres = nullptr;
};

struct KMeansResult {
  int clusters = 0;  // k actually produced (< requested when the data has fewer
                     // distinct points); every cluster is non-empty
  std::size_t dim = 0;
  std::vector<int32_t> labels;  // per point, in [0, clusters)
  std::vector<double> centres;  // clusters x dim, row-major: the mean of each cluster's points
  std::vector<uint64_t> sizes;  // points per cluster
  std::vector<double> inertia;  // per cluster: sum of squared distances to its centre
  double total_inertia = 0.0;   // sum of inertia
  int iterations = 0;           // Lloyd iterations run
  bool converged = false;       // true when the last iteration changed no label
  int empty_repairs = 0;        // clusters re-seeded because they became empty
};

// Clusters `points`. Errors (clothbake::Error, ExitCode::Input): no points, dim == 0,
// clusters < 1, max_iterations < 1, a non-finite coordinate (naming the point and coordinate) or
// initial centre.
// Safe on untrusted values (every finite input gives a valid result). Requested clusters larger
// than the number of distinct points give fewer clusters (KMeansResult::clusters).
KMeansResult kmeans(const PointSet& points, const KMeansOptions& options);

// Index of the nearest centre to `point` (dim coordinates) among `clusters` centres (row-major,
// double), ties to the lower index; writes the squared distance. For callers that label new
// points with a finished clustering.
int nearest_centre(const float* point, const double* centres, int clusters, std::size_t dim,
                   double* distance2);

}  // namespace clothbake::cluster

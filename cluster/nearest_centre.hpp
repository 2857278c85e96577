// Nearest-centre search for K-means assignment: brute force over every centre in double precision,
// ties to the lower index (kmeans.hpp says why there is no kd-tree). Internal to cluster/
// (kmeans.cpp and benchmarks/cluster use it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "cluster/kmeans.hpp"

namespace clothbake::cluster {

class CentreSearch {
 public:
  virtual ~CentreSearch() = default;
  // Labels points [begin, end) of `points`; labels and distance2 are indexed by point. Safe to call
  // concurrently on disjoint ranges.
  virtual void assign(const PointSet& points, std::size_t begin, std::size_t end, int32_t* labels,
                      double* distance2) const = 0;
};

// A search over `clusters` centres (row-major, dim doubles each; copied).
std::unique_ptr<CentreSearch> make_centre_search(const double* centres, int clusters,
                                                 std::size_t dim);

// Squared Euclidean distance between a float point and a double centre, summed in a fixed order.
double squared_distance(const float* point, const double* centre, std::size_t dim);

}  // namespace clothbake::cluster

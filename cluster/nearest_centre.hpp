// Nearest-centre search for K-means assignment: brute force or a FLANN kd-tree over the centres.
// Internal to cluster/ (kmeans.cpp and benchmarks/cluster use it).
//
// Both assign a range of points to their nearest centre and write the label and the squared
// distance (in double, recomputed from the chosen centre so that both paths report comparable
// inertia). Brute force compares every centre in double precision, ties to the lower index. The
// kd-tree (flann::KDTreeSingleIndex, exact search) compares in float: it returns the true nearest
// centre up to float rounding, so a near-tie may resolve to the other centre.
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
std::unique_ptr<CentreSearch> make_centre_search(NearestSearch kind, const double* centres,
                                                 int clusters, std::size_t dim);

// Squared Euclidean distance between a float point and a double centre, summed in a fixed order.
double squared_distance(const float* point, const double* centre, std::size_t dim);

}  // namespace clothbake::cluster

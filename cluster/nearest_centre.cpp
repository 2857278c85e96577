// Brute-force nearest-centre search (nearest_centre.hpp).
#include "cluster/nearest_centre.hpp"

#include <limits>

namespace clothbake::cluster {

double squared_distance(const float* point, const double* centre, std::size_t dim) {
  // Four interleaved partial sums: a fixed order (deterministic) that still pipelines well.
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  std::size_t j = 0;
  for (; j + 4 <= dim; j += 4) {
    const double d0 = double(point[j]) - centre[j];
    const double d1 = double(point[j + 1]) - centre[j + 1];
    const double d2 = double(point[j + 2]) - centre[j + 2];
    const double d3 = double(point[j + 3]) - centre[j + 3];
    s0 += d0 * d0;
    s1 += d1 * d1;
    s2 += d2 * d2;
    s3 += d3 * d3;
  }
  for (; j < dim; ++j) {
    const double d = double(point[j]) - centre[j];
    s0 += d * d;
  }
  return (s0 + s1) + (s2 + s3);
}

int nearest_centre(const float* point, const double* centres, int clusters, std::size_t dim,
                   double* distance2) {
  int best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (int c = 0; c < clusters; ++c) {
    const double d = squared_distance(point, centres + std::size_t(c) * dim, dim);
    if (d < best_d) {  // strict: ties keep the lower index
      best_d = d;
      best = c;
    }
  }
  if (distance2) *distance2 = best_d;
  return best;
}

namespace {

class BruteForceSearch final : public CentreSearch {
 public:
  BruteForceSearch(const double* centres, int clusters, std::size_t dim)
      : centres_(centres, centres + std::size_t(clusters) * dim), clusters_(clusters), dim_(dim) {}

  void assign(const PointSet& points, std::size_t begin, std::size_t end, int32_t* labels,
              double* distance2) const override {
    for (std::size_t i = begin; i < end; ++i)
      labels[i] = nearest_centre(points.point(i), centres_.data(), clusters_, dim_, &distance2[i]);
  }

 private:
  std::vector<double> centres_;
  int clusters_;
  std::size_t dim_;
};

}  // namespace

std::unique_ptr<CentreSearch> make_centre_search(const double* centres, int clusters,
                                                 std::size_t dim) {
  return std::make_unique<BruteForceSearch>(centres, clusters, dim);
}

}  // namespace clothbake::cluster

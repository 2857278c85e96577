// Generic K-means (cluster/kmeans.hpp): exact recovery of separated blobs, Lloyd optimality
// conditions, statistics against brute-force recomputation, determinism for any thread count,
// empty-cluster repair, degenerate data, and errors.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "cluster/kmeans.hpp"
#include "cluster/nearest_centre.hpp"
#include "common/error.hpp"

using namespace clothbake::cluster;

namespace {

struct Blobs {
  std::vector<float> data;
  std::vector<int> truth;
  std::size_t dim = 0;
  PointSet points() const { return {data.data(), truth.size(), dim}; }
};

// `k` well separated Gaussian blobs (centres 100 apart, sigma 1) of random sizes in `dim` dims.
Blobs make_blobs(int k, std::size_t dim, std::size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<std::vector<double>> centre(std::size_t(k), std::vector<double>(dim, 0.0));
  for (int c = 0; c < k; ++c)
    for (std::size_t j = 0; j < dim; ++j)
      centre[std::size_t(c)][j] = 100.0 * ((c >> j) & 1) + 37.0 * c * (j == 0);
  Blobs b;
  b.dim = dim;
  for (std::size_t i = 0; i < n; ++i) {
    int c = int(rng() % uint64_t(k));
    b.truth.push_back(c);
    for (std::size_t j = 0; j < dim; ++j)
      b.data.push_back(float(centre[std::size_t(c)][j] + noise(rng)));
  }
  return b;
}

// True when labels equal truth up to a permutation of cluster ids.
bool same_partition(const std::vector<int32_t>& labels, const std::vector<int>& truth) {
  std::map<int, int> forward, backward;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    auto [f, fnew] = forward.emplace(truth[i], labels[i]);
    auto [b, bnew] = backward.emplace(labels[i], truth[i]);
    if (f->second != labels[i] || b->second != truth[i]) return false;
  }
  return true;
}

KMeansResult run_with_threads(const PointSet& p, const KMeansOptions& o, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  return kmeans(p, o);
}

}  // namespace

TEST(KMeans, RecoversSeparatedBlobsExactly) {
  Blobs b = make_blobs(8, 11, 5000, 3);
  KMeansOptions o;
  o.clusters = 8;
  KMeansResult r = kmeans(b.points(), o);
  ASSERT_EQ(r.clusters, 8);
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(same_partition(r.labels, b.truth));
}

TEST(KMeans, ResultSatisfiesLloydConditionsAndStatisticsMatchBruteForce) {
  // Overlapping clusters: a genuine local optimum, not a trivially separable case.
  std::mt19937_64 rng(11);
  std::normal_distribution<float> g(0.0f, 1.0f);
  const std::size_t n = 3000, dim = 5;
  std::vector<float> data(n * dim);
  for (float& v : data)
    v = g(rng);
  KMeansOptions o;
  o.clusters = 6;
  o.max_iterations = 500;
  KMeansResult r = kmeans({data.data(), n, dim}, o);
  ASSERT_TRUE(r.converged);
  ASSERT_EQ(r.clusters, 6);
  std::vector<double> mean(std::size_t(r.clusters) * dim, 0.0),
      inertia(std::size_t(r.clusters), 0.0);
  std::vector<uint64_t> size(std::size_t(r.clusters), 0);
  for (std::size_t i = 0; i < n; ++i) {
    // Every point sits with its nearest centre.
    double d2;
    int nearest = nearest_centre(&data[i * dim], r.centres.data(), r.clusters, dim, &d2);
    ASSERT_EQ(nearest, r.labels[i]) << "point " << i;
    ++size[std::size_t(r.labels[i])];
    for (std::size_t j = 0; j < dim; ++j)
      mean[std::size_t(r.labels[i]) * dim + j] += data[i * dim + j];
  }
  for (int c = 0; c < r.clusters; ++c) {
    EXPECT_EQ(size[std::size_t(c)], r.sizes[std::size_t(c)]);
    for (std::size_t j = 0; j < dim; ++j)
      EXPECT_NEAR(mean[std::size_t(c) * dim + j] / double(size[std::size_t(c)]),
                  r.centres[std::size_t(c) * dim + j], 1e-12);
  }
  double total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double d = 0;
    for (std::size_t j = 0; j < dim; ++j) {
      double e = data[i * dim + j] - r.centres[std::size_t(r.labels[i]) * dim + j];
      d += e * e;
    }
    inertia[std::size_t(r.labels[i])] += d;
    total += d;
  }
  for (int c = 0; c < r.clusters; ++c)
    EXPECT_NEAR(inertia[std::size_t(c)], r.inertia[std::size_t(c)], 1e-9 * total);
  EXPECT_NEAR(total, r.total_inertia, 1e-9 * total);
}

TEST(KMeans, BitIdenticalForAnyThreadCountAndRepeatable) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const std::size_t n = 20000, dim = 11;  // many blocks, uneven last block
  std::vector<float> data(n * dim);
  for (float& v : data)
    v = u(rng);
  KMeansOptions o;
  o.clusters = 8;
  o.seed = 42;
  KMeansResult one = run_with_threads({data.data(), n, dim}, o, 1);
  KMeansResult two = run_with_threads({data.data(), n, dim}, o, 2);
  KMeansResult again = run_with_threads({data.data(), n, dim}, o, 2);
  EXPECT_EQ(one.labels, two.labels);
  EXPECT_EQ(one.centres, two.centres);  // bitwise: exact double equality
  EXPECT_EQ(one.inertia, two.inertia);
  EXPECT_EQ(one.iterations, two.iterations);
  EXPECT_EQ(two.labels, again.labels);
  EXPECT_EQ(two.centres, again.centres);
  // A different seed is allowed to (and here does) give a different local optimum or ordering.
  o.seed = 43;
  KMeansResult other = run_with_threads({data.data(), n, dim}, o, 2);
  EXPECT_NE(other.centres, two.centres);
}

TEST(KMeans, EmptyClusterIsRepairedWithTheFarthestPoint) {
  // Two tight groups; the warm start puts centre 2 far away from every point, so it is empty after
  // the first assignment. The repair must move the point farthest from its centre into it.
  std::vector<float> data = {0.0f, 0.1f, -0.1f, 0.05f, 10.0f, 10.1f, 9.9f, 13.0f};
  std::vector<double> start = {0.0, 10.0, 1000.0};
  KMeansOptions o;
  o.clusters = 3;
  o.initial_centres = start.data();
  KMeansResult r = kmeans({data.data(), data.size(), 1}, o);
  EXPECT_GE(r.empty_repairs, 1);
  ASSERT_EQ(r.clusters, 3);
  // 13.0 (distance 3 from the first group-2 centre) ends alone in its own cluster.
  EXPECT_EQ(r.sizes[2], 1u);
  EXPECT_EQ(r.labels[7], 2);
  EXPECT_DOUBLE_EQ(r.centres[2], 13.0);
  for (uint64_t s : r.sizes)
    EXPECT_GT(s, 0u);
}

TEST(KMeans, FewerDistinctPointsThanClusters) {
  std::vector<float> same(50 * 3, 2.5f);
  KMeansOptions o;
  o.clusters = 8;
  KMeansResult r = kmeans({same.data(), 50, 3}, o);
  EXPECT_EQ(r.clusters, 1);
  EXPECT_EQ(r.sizes[0], 50u);
  EXPECT_EQ(r.total_inertia, 0.0);
  // Three distinct values, k = 8: exactly three clusters, each one value.
  std::vector<float> three;
  for (int i = 0; i < 30; ++i)
    three.push_back(float(i % 3));
  r = kmeans({three.data(), 30, 1}, o);
  EXPECT_EQ(r.clusters, 3);
  EXPECT_EQ(r.total_inertia, 0.0);
  // More clusters than points.
  std::vector<float> two = {0.0f, 1.0f};
  r = kmeans({two.data(), 2, 1}, o);
  EXPECT_EQ(r.clusters, 2);
}

TEST(KMeans, RejectsBadInput) {
  std::vector<float> data = {0.0f, 1.0f, 2.0f, 3.0f};
  KMeansOptions o;
  o.clusters = 0;
  EXPECT_THROW(kmeans({data.data(), 4, 1}, o), clothbake::Error);
  o.clusters = 2;
  EXPECT_THROW(kmeans({data.data(), 0, 1}, o), clothbake::Error);
  data[2] = std::numeric_limits<float>::quiet_NaN();
  try {
    kmeans({data.data(), 2, 2}, o);
    FAIL() << "NaN accepted";
  } catch (const clothbake::Error& e) {
    EXPECT_EQ(e.code(), clothbake::ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("point 1 coordinate 0"), std::string::npos) << e.what();
  }
}

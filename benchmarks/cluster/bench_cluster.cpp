// Nearest-centre search for K-means (cluster/nearest_centre.hpp), brute force, one thread, points
// per second; and whole K-means runs. (The FLANN kd-tree it was measured against is gone, see
// docs/tables.md "Nearest-centre search".)
//   build-*/bin/bench_cluster --benchmark_filter=Assign
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <random>
#include <vector>

#include "cluster/kmeans.hpp"
#include "cluster/nearest_centre.hpp"

using namespace clothbake::cluster;

namespace {

std::vector<float> random_points(std::size_t n, std::size_t dim, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<float> p(n * dim);
  for (float& v : p)
    v = g(rng);
  return p;
}

// Args: clusters, dim.
void BM_Assign(benchmark::State& state) {
  const int k = int(state.range(0));
  const std::size_t dim = std::size_t(state.range(1));
  const std::size_t n = 65536;
  auto points = random_points(n, dim, 1);
  auto centres_f = random_points(std::size_t(k), dim, 2);
  std::vector<double> centres(centres_f.begin(), centres_f.end());
  auto search = make_centre_search(centres.data(), k, dim);
  std::vector<int32_t> labels(n);
  std::vector<double> d2(n);
  PointSet set{points.data(), n, dim};
  for (auto _ : state) {
    search->assign(set, 0, n, labels.data(), d2.data());
    benchmark::DoNotOptimize(labels.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(n));
}
BENCHMARK(BM_Assign)->ArgsProduct({{8, 64, 256, 1024}, {3, 11, 64}})->Unit(benchmark::kMillisecond);

// Whole K-means on 256^2 ASG-like embeddings (11 dims, 8 clusters), both cores.
void BM_KMeansAsgSized(benchmark::State& state) {
  auto points = random_points(65536, 11, 3);
  KMeansOptions o;
  o.clusters = 8;
  o.max_iterations = 100;
  int iterations = 0;
  for (auto _ : state) {
    KMeansResult r = kmeans({points.data(), 65536, 11}, o);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.labels.data());
  }
  state.counters["lloyd_iterations"] = iterations;
}
BENCHMARK(BM_KMeansAsgSized)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

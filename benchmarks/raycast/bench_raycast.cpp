// Throughput of the ray-casting stages on a woven tile (docs/raycast.md, "Performance").
//   build-*/bin/bench_raycast                                   (everything, ~1 min on 2 cores)
//   build-*/bin/bench_raycast --benchmark_filter='Stages/256'   (the 256^2 x 32^2 target)
//   build-*/bin/bench_raycast --benchmark_filter='ParallaxStage' (parallax alone, 1 and 2 threads)
// Counters: rays/s over all threads (wall clock), segments per ray; fits/s (texels given a
// record per second) for the ASG fit, the share of distinct sample patterns and the objective
// evaluations per fit run.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <chrono>
#include <map>

#include "common/diagnostics.hpp"
#include "raycast/parallax.hpp"
#include "raycast/visibility.hpp"
#include "tests/raycast/synthetic_fields.hpp"

namespace {

using namespace clothbake;

// The plain weave of the tests, 4 threads per tile, 0.12 tile sides tall.
const FabricMaps& weave(int n) {
  static std::map<int, FabricMaps> cache;
  auto it = cache.find(n);
  if (it == cache.end()) it = cache.emplace(n, raycast::rctest::plain_weave_maps(n)).first;
  return it->second;
}

// Args: resolution, directions per side, rings (-1 automatic), threads.
void BM_Parallax(benchmark::State& state) {
  const int n = int(state.range(0));
  raycast::ParallaxSettings settings;
  settings.dirs = int(state.range(1));
  settings.rings = int(state.range(2));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(3)));
  const FabricMaps& maps = weave(n);
  uint64_t rays = 0, segments = 0;
  for (auto _ : state) {
    raycast::ParallaxTable table = raycast::bake_parallax(maps, settings);
    rays += table.stats.rays;
    segments += table.stats.segments;
    benchmark::DoNotOptimize(table.depth.data());
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["segments/ray"] = double(segments) / double(rays);
}
BENCHMARK(BM_Parallax)
    ->Args({128, 32, 0, 1})
    ->Args({128, 32, 1, 1})
    ->Args({128, 32, 3, 1})
    ->Args({128, 32, -1, 1})
    ->Args({128, 32, -1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The parallax stage as a bake runs it at the size: the table, then its SATs. Args:
// resolution, directions per side, threads. Wall time per part from a steady clock; the CPU
// column is the process's CPU time (all threads). Counters: rays/s over the whole stage (wall,
// SAT included) and over the ray casting alone, and the SAT build's seconds.
void BM_ParallaxStage(benchmark::State& state) {
  const int n = int(state.range(0));
  raycast::ParallaxSettings settings;
  settings.dirs = int(state.range(1));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(2)));
  const FabricMaps& maps = weave(n);
  uint64_t rays = 0;
  double cast_seconds = 0, sat_seconds = 0;
  using Clock = std::chrono::steady_clock;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    raycast::ParallaxTable table = raycast::bake_parallax(maps, settings);
    const auto t1 = Clock::now();
    std::vector<uint32_t> sat = raycast::parallax_sat(table);
    const auto t2 = Clock::now();
    rays += table.stats.rays;
    cast_seconds += std::chrono::duration<double>(t1 - t0).count();
    sat_seconds += std::chrono::duration<double>(t2 - t1).count();
    benchmark::DoNotOptimize(sat.data());
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["cast_rays/s"] = double(rays) / cast_seconds;
  state.counters["sat_s"] = sat_seconds / double(state.iterations());
}
BENCHMARK(BM_ParallaxStage)
    ->Args({256, 32, 1})
    ->Args({256, 32, 2})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Iterations(1);

// Args: resolution, directions per side, rings, threads.
void BM_Visibility(benchmark::State& state) {
  const int n = int(state.range(0));
  raycast::VisibilitySettings settings;
  settings.dirs = int(state.range(1));
  settings.rings = int(state.range(2));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(3)));
  const FabricMaps& maps = weave(n);
  uint64_t rays = 0, segments = 0;
  for (auto _ : state) {
    raycast::VisibilitySamples v = raycast::sample_visibility(maps, settings);
    rays += v.rays;
    segments += v.segments;
    benchmark::DoNotOptimize(v.bits.data());
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  state.counters["segments/ray"] = double(segments) / double(rays);
}
BENCHMARK(BM_Visibility)
    ->Args({128, 32, 0, 1})
    ->Args({128, 32, 1, 1})
    ->Args({128, 32, 3, 1})
    ->Args({128, 32, -1, 1})
    ->Args({128, 32, -1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Args: resolution, directions per side, threads.
void BM_AsgFit(benchmark::State& state) {
  const int n = int(state.range(0));
  raycast::VisibilitySettings settings;
  settings.dirs = int(state.range(1));
  settings.fit_warn_rms = 10;  // quiet
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(2)));
  raycast::VisibilitySamples v = raycast::sample_visibility(weave(n), settings);
  uint64_t fits = 0, distinct = 0, evaluations = 0;
  double mean_error = 0;
  for (auto _ : state) {
    raycast::VisibilityAsgs a = raycast::fit_visibility(v, settings);
    fits += a.records.size();
    distinct += a.distinct_patterns;
    evaluations += a.fit_evaluations;
    mean_error = a.mean_fit_error;
    benchmark::DoNotOptimize(a.records.data());
  }
  state.counters["fits/s"] = benchmark::Counter(double(fits), benchmark::Counter::kIsRate);
  // Objective evaluations per fit actually run (distinct patterns are fitted once).
  state.counters["evals/fit"] = double(evaluations) / double(distinct);
  state.counters["distinct"] = double(distinct) / double(fits);
  state.counters["mean_rms"] = mean_error;
}
BENCHMARK(BM_AsgFit)
    ->Args({128, 32, 1})
    ->Args({128, 32, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Both stages as a bake runs them: parallax table + SAT, visibility + ASG fit. Args: resolution,
// directions per side (both stages), threads. The target: 256, 32, 2 in <= 15 s.
void BM_Stages(benchmark::State& state) {
  const int n = int(state.range(0));
  raycast::ParallaxSettings parallax;
  parallax.dirs = int(state.range(1));
  raycast::VisibilitySettings visibility;
  visibility.dirs = int(state.range(1));
  visibility.fit_warn_rms = 10;
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(2)));
  const FabricMaps& maps = weave(n);
  uint64_t rays = 0;
  for (auto _ : state) {
    raycast::ParallaxTable table = raycast::bake_parallax(maps, parallax);
    std::vector<uint32_t> sat = raycast::parallax_sat(table);
    raycast::VisibilitySamples v = raycast::sample_visibility(maps, visibility);
    raycast::VisibilityAsgs a = raycast::fit_visibility(v, visibility);
    rays += table.stats.rays + v.rays;
    benchmark::DoNotOptimize(sat.data());
    benchmark::DoNotOptimize(a.records.data());
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Stages)
    ->Args({256, 32, 2})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();

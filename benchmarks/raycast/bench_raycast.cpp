// Ray throughput of the ray-casting stages on a woven tile (docs/raycast.md, "Performance").
//   build-*/bin/bench_raycast --benchmark_filter=Parallax
// Counters: rays/s over all threads (wall clock), segments per ray.
#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include "bake/raycast/parallax.hpp"
#include "tests/raycast/synthetic_fields.hpp"

namespace {

using namespace clothbake;

// Args: resolution, directions per side, rings (-1 automatic), threads.
void BM_Parallax(benchmark::State& state) {
  const int n = int(state.range(0));
  raycast::ParallaxSettings settings;
  settings.dirs = int(state.range(1));
  settings.rings = int(state.range(2));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(3)));
  FabricMaps maps = raycast::rctest::plain_weave_maps(n);
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
    ->Args({128, 32, 0, 2})
    ->Args({128, 32, 1, 2})
    ->Args({128, 32, 2, 2})
    ->Args({128, 32, -1, 1})
    ->Args({256, 32, -1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

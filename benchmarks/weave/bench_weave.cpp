// Speed of procedural weave map generation and WIF import.
//   bench_weave --benchmark_filter=Maps   (targets: 256^2 well under 1 s, 2048^2 a few seconds)
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <fstream>
#include <sstream>

#include "bake/inputs/weave_maps.hpp"
#include "bake/inputs/wif.hpp"
#include "common/diagnostics.hpp"

using namespace clothbake;
using namespace clothbake::weave;

namespace {

WeaveSpec twill_spec() {
  WeaveSpec spec;
  spec.matrix = twill(2, 1, false);
  spec.warp = {0.5, 0.85, 0.15, 20.0};
  spec.weft = {0.6, 0.9, 0.18, -20.0};
  spec.end_colors = {{0.8, 0.1, 0.1}, {0.1, 0.8, 0.1}, {0.1, 0.1, 0.8}};
  return spec;
}

// Maps at N x N with every core (args: N, threads; 0 = all).
void BM_Maps(benchmark::State& state) {
  const int n = int(state.range(0));
  const int threads = int(state.range(1));
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  std::size_t(threads));
  const WeaveSpec spec = twill_spec();
  for (auto _ : state) {
    FabricMaps maps = generate_weave_maps(spec, n);
    benchmark::DoNotOptimize(maps.height.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(n) * n);
  state.counters["texels/s"] =
      benchmark::Counter(double(n) * n, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Maps)
    ->Args({256, 0})
    ->Args({256, 1})
    ->Args({1024, 0})
    ->Args({2048, 0})
    ->Args({2048, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Sample(benchmark::State& state) {
  const WeaveSurface surface(twill_spec());
  double u = 0.123, v = 0.456, sum = 0;
  for (auto _ : state) {
    sum += surface.sample(u, v).height;
    u += 0.0137;
    v += 0.0291;
  }
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_Sample);

void BM_ParseWif(benchmark::State& state) {
  std::ifstream in(std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/wif/diamond-point-twill.wif");
  std::stringstream text;
  text << in.rdbuf();
  set_quiet(true);
  for (auto _ : state) {
    WifDraft d = parse_wif(text.str(), "diamond-point-twill.wif");
    benchmark::DoNotOptimize(d.spec.matrix.cells.data());
  }
}
BENCHMARK(BM_ParseWif);

}  // namespace

BENCHMARK_MAIN();

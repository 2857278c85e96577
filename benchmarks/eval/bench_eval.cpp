// One footprint estimate of the evaluator on one core: every method, footprints of side 1, 32, 256
// and 4096 texels at random positions, random reflection directions (cycled from a fixed set).
//
//   CLOTHBAKE_BENCH_ASSET=twill.cbk bench_eval [--benchmark_filter=...]
//   CLOTHBAKE_BENCH_TABLES=raw|compressed (default: auto, as the evaluator opens it)
// Items per second: estimates (Multiscale*, Brute), samples (BrutePerSample), texels (Reference).
// Target (docs/evaluator.md, "Speed"): Multiscale at 2 spp <= 3 us per footprint in renderer
// order on one core.
// *Scanlines: the same in a renderer's order (abutting footprints, one direction pair per row).
// Lazily built structures are warmed up before timing (setup()).
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "eval/evaluator.hpp"

namespace clothbake::eval {
namespace {

struct Setup {
  reader::Asset asset;
  Evaluator evaluator;
  std::vector<std::array<double, 6>> directions;  // wi, wo
};

Setup& setup() {
  static std::unique_ptr<Setup> s = [] {
    auto s = std::make_unique<Setup>();
    const char* path = std::getenv("CLOTHBAKE_BENCH_ASSET");
    if (path == nullptr) {
      std::fprintf(stderr, "bench_eval: set CLOTHBAKE_BENCH_ASSET to a baked asset (.cbk)\n");
      std::exit(2);
    }
    Status st = s->asset.open_file(path);
    EvalOptions options;
    if (const char* t = std::getenv("CLOTHBAKE_BENCH_TABLES"))
      options.tables = std::strcmp(t, "raw") == 0 ? TableChoice::Raw : TableChoice::Compressed;
    if (st.ok()) st = s->evaluator.open(s->asset, options);
    if (!st.ok()) {
      std::fprintf(stderr, "bench_eval: %s: %s\n", path, st.message());
      std::exit(2);
    }
    std::fprintf(stderr, "bench_eval: %s, %u^2 texels, %u clusters, %s tables\n", path,
                 s->evaluator.resolution(), s->evaluator.cluster_count(),
                 s->evaluator.table_source());
    Rng rng(42);
    for (int k = 0; k < 256; ++k) {
      auto hemisphere = [&](double min_z) {
        const double z = min_z + (1.0 - min_z) * rng.uniform(),
                     phi = 6.283185307179586 * rng.uniform();
        const double r = std::sqrt(1.0 - z * z);
        return std::array<double, 3>{r * std::cos(phi), r * std::sin(phi), z};
      };
      const auto wi = hemisphere(0.2), wo = hemisphere(0.2);
      s->directions.push_back({wi[0], wi[1], wi[2], wo[0], wo[1], wo[2]});
    }
    return s;
  }();
  return *s;
}

void run(benchmark::State& state, Method method, uint32_t spp) {
  Setup& s = setup();
  const double side = double(state.range(0));
  const double n = s.evaluator.resolution();
  Rng rng(7);
  std::vector<Footprint> footprints;
  for (int k = 0; k < 1024; ++k) {
    const double x = rng.uniform() * n, y = rng.uniform() * n;
    footprints.push_back({x, y, x + side, y + side});
  }
  // Warm-up, untimed: what the method builds on first use (the parallax planes of the view bins
  // and their references, decoded once: 0.5 s for all of the twill's; the per-bin block means or
  // parallax SATs) is built here for every direction the loop cycles through, as a renderer's
  // first pixels would, so that the figure is the steady state per estimate.
  Estimate e;
  for (const auto& d : s.directions)
    for (int k = 0; k < 16; ++k)  // every view bin an estimate may draw
      (void)s.evaluator.estimate(footprints[0], d.data(), d.data() + 3, method, spp, rng, kAllLobes,
                                 &e);
  size_t k = 0;
  for (auto _ : state) {
    const auto& d = s.directions[k % s.directions.size()];
    const Status st = s.evaluator.estimate(footprints[k % footprints.size()], d.data(),
                                           d.data() + 3, method, spp, rng, kAllLobes, &e);
    if (!st.ok()) state.SkipWithError(st.message());
    benchmark::DoNotOptimize(e);
    ++k;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

// Renderer order: rows of 64 abutting footprints (neighbouring pixels of a far-field swatch), one
// direction pair per row (a distant light and camera change the directions little from one pixel
// to the next), the next row below the last. The figure a renderer sees per pixel, where run()'s
// random positions and directions, a new part of every table per estimate, are the worst case.
void run_scanlines(benchmark::State& state, Method method, uint32_t spp) {
  Setup& s = setup();
  const double side = double(state.range(0));
  constexpr int kRow = 64;
  Rng rng(7);
  Estimate e;
  for (const auto& d : s.directions) {  // warm-up, as in run()
    const Footprint p{0.0, 0.0, side, side};
    for (int k = 0; k < 16; ++k)
      (void)s.evaluator.estimate(p, d.data(), d.data() + 3, method, spp, rng, kAllLobes, &e);
  }
  size_t k = 0;
  for (auto _ : state) {
    const size_t row = k / kRow;
    const auto& d = s.directions[row % s.directions.size()];
    const double x = double(k % kRow) * side, y = double(row) * side;
    const Status st = s.evaluator.estimate({x, y, x + side, y + side}, d.data(), d.data() + 3,
                                           method, spp, rng, kAllLobes, &e);
    if (!st.ok()) state.SkipWithError(st.message());
    benchmark::DoNotOptimize(e);
    ++k;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

void BM_MultiscaleScanlines(benchmark::State& state) {
  run_scanlines(state, Method::Multiscale, 2);
}
void BM_Brute2sppScanlines(benchmark::State& state) {
  run_scanlines(state, Method::Brute, 2);
}

void BM_Multiscale(benchmark::State& state) {
  run(state, Method::Multiscale, 2);
}
void BM_MultiscalePaper(benchmark::State& state) {
  run(state, Method::MultiscalePaper, 2);
}
void BM_Brute2spp(benchmark::State& state) {
  run(state, Method::Brute, 2);
}

void BM_BrutePerSample(benchmark::State& state) {
  run(state, Method::Brute, 64);
  state.SetItemsProcessed(int64_t(state.iterations()) * 64);
}

void BM_ReferencePerTexel(benchmark::State& state) {
  run(state, Method::Reference, 1);
  state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0) * state.range(0));
}

// 256 and 4096: whole periods only (at N = 256); 400 and 640: 1.56 and 2.5 tiles, a remainder.
BENCHMARK(BM_Multiscale)->Arg(1)->Arg(32)->Arg(256)->Arg(400)->Arg(640)->Arg(4096);
BENCHMARK(BM_MultiscalePaper)->Arg(1)->Arg(32)->Arg(256)->Arg(4096);
BENCHMARK(BM_Brute2spp)->Arg(32)->Arg(256)->Arg(640);
BENCHMARK(BM_BrutePerSample)->Arg(32);
BENCHMARK(BM_ReferencePerTexel)->Arg(4)->Arg(32);
BENCHMARK(BM_MultiscaleScanlines)
    ->Arg(1)
    ->Arg(32)
    ->Arg(64)
    ->Arg(128)
    ->Arg(180)
    ->Arg(256)
    ->Arg(400)
    ->Arg(640)
    ->Arg(4096);
BENCHMARK(BM_Brute2sppScanlines)->Arg(32)->Arg(128)->Arg(256)->Arg(640);

}  // namespace
}  // namespace clothbake::eval

BENCHMARK_MAIN();

// Parallax queries on the raw form (16-bit codes + stored SATs) of a 256^2 x 32^2 table of
// pseudo-random codes (query cost does not depend on the content; docs/performance.md,
// "Compressed parallax").
//
// The compressed (hierarchical, entropy-coded) form is measured on a real asset, since its cost
// depends on the content: CLOTHBAKE_BENCH_ASSET=twill.cbk (a default bake); without it those
// benchmarks skip.
//
//   CLOTHBAKE_BENCH_ASSET=twill.cbk build/bin/bench_parallax --benchmark_min_time=0.3
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>

#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/writer/asset_writer.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"

using namespace clothbake;

namespace {

constexpr int kN = 256, kDirs = 32;

struct Fixture {
  raycast::ParallaxTable table;
  std::vector<uint64_t> raw_bytes;
  reader::Asset raw_asset;
  reader::ParallaxView raw;
  Fixture() {
    table.resolution = kN;
    table.dirs = kDirs;
    table.depth_scale = 0.25 / 65535;
    table.depth.resize(std::size_t(kDirs) * kDirs * kN * kN);
    std::mt19937_64 rng(1);
    for (auto& c : table.depth)
      c = uint16_t(rng() >> 48);
    raycast::ParallaxTable copy = table;
    auto rs = raycast::parallax_sections(std::move(copy));
    auto store = [](const std::vector<formats::Section>& s, std::vector<uint64_t>* out) {
      auto bytes = formats::serialize_asset(s);
      out->resize((bytes.size() + 7) / 8);
      std::memcpy(out->data(), bytes.data(), bytes.size());
      return bytes.size();
    };
    const std::size_t raw_size = store(rs, &raw_bytes);
    (void)raw_asset.open_memory(raw_bytes.data(), raw_size);
    (void)raw.open(raw_asset);
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

std::vector<double> positions() {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, kN);
  std::vector<double> p(2 * 4096);
  for (double& x : p)
    x = u(rng);
  return p;
}

void BM_TexelRaw(benchmark::State& state) {
  const reader::ParallaxView& view = fixture().raw;
  const auto p = positions();
  const double v[3] = {0.3, -0.2, 0.9};
  reader::ParallaxSample s;
  std::size_t i = 0;
  for (auto _ : state) {
    (void)view.depth(int64_t(p[2 * (i & 4095)]), int64_t(p[2 * (i & 4095) + 1]), v, &s);
    benchmark::DoNotOptimize(s.r);
    ++i;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

void BM_FootprintRaw(benchmark::State& state) {
  const reader::ParallaxView& view = fixture().raw;
  const auto p = positions();
  const double size = double(state.range(0)) + 0.5;
  const double v[3] = {0.3, -0.2, 0.9};
  reader::ParallaxSample s;
  std::size_t i = 0;
  for (auto _ : state) {
    const double x0 = p[2 * (i & 4095)], y0 = p[2 * (i & 4095) + 1];
    (void)view.footprint_depth({x0, y0, x0 + size, y0 + size}, v, &s);
    benchmark::DoNotOptimize(s.r);
    ++i;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

// The asset of CLOTHBAKE_BENCH_ASSET in memory, with its compressed parallax opened and, for
// the queries, every plane decoded and every SAT built (a renderer's steady state).
struct EntropyFixture {
  std::vector<uint64_t> bytes;
  std::size_t size = 0;
  reader::Asset asset;
  reader::ParallaxView view;
  bool ok = false;
  EntropyFixture() {
    const char* path = std::getenv("CLOTHBAKE_BENCH_ASSET");
    if (!path) return;
    std::ifstream in(path, std::ios::binary);
    std::vector<char> b((std::istreambuf_iterator<char>(in)), {});
    size = b.size();
    bytes.resize((size + 7) / 8);
    std::memcpy(bytes.data(), b.data(), size);
    ok = asset.open_memory(bytes.data(), size).ok() &&
         view.open(asset, reader::ParallaxSource::Compressed).ok();
  }
};

EntropyFixture& entropy() {
  static EntropyFixture f;
  return f;
}

void BM_EntropyOpenWithChecksums(benchmark::State& state) {
  EntropyFixture& f = entropy();
  if (!f.ok)
    return state.SkipWithError("set CLOTHBAKE_BENCH_ASSET to an asset with parallax_entropy");
  for (auto _ : state) {
    reader::Asset a;
    reader::ParallaxView v;
    benchmark::DoNotOptimize(a.open_memory(f.bytes.data(), f.size).ok() &&
                             reader::verify_checksums(a).ok() && v.open(a).ok());
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(f.size));
}

void BM_EntropyDecodeAll(benchmark::State& state) {
  EntropyFixture& f = entropy();
  if (!f.ok)
    return state.SkipWithError("set CLOTHBAKE_BENCH_ASSET to an asset with parallax_entropy");
  for (auto _ : state)
    benchmark::DoNotOptimize(f.view.decode_all().ok());
  const int64_t codes =
      int64_t(f.view.dirs()) * f.view.dirs() * f.view.resolution() * f.view.resolution();
  state.SetItemsProcessed(int64_t(state.iterations()) * codes);
}

void entropy_steady(EntropyFixture& f) {
  static bool done = false;
  if (done) return;
  for (uint32_t b = 0; b < f.view.dirs() * f.view.dirs(); ++b)
    (void)f.view.ensure_sat(b);
  done = true;
}

void BM_TexelEntropy(benchmark::State& state) {
  EntropyFixture& f = entropy();
  if (!f.ok)
    return state.SkipWithError("set CLOTHBAKE_BENCH_ASSET to an asset with parallax_entropy");
  entropy_steady(f);
  const auto p = positions();
  const double v[3] = {0.3, -0.2, 0.9};
  reader::ParallaxSample s;
  std::size_t i = 0;
  for (auto _ : state) {
    (void)f.view.depth(int64_t(p[2 * (i & 4095)]), int64_t(p[2 * (i & 4095) + 1]), v, &s);
    benchmark::DoNotOptimize(s.r);
    ++i;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

void BM_FootprintEntropy(benchmark::State& state) {
  EntropyFixture& f = entropy();
  if (!f.ok)
    return state.SkipWithError("set CLOTHBAKE_BENCH_ASSET to an asset with parallax_entropy");
  entropy_steady(f);
  const auto p = positions();
  const double size = double(state.range(0)) + 0.5;
  const double v[3] = {0.3, -0.2, 0.9};
  reader::ParallaxSample s;
  std::size_t i = 0;
  for (auto _ : state) {
    const double x0 = p[2 * (i & 4095)], y0 = p[2 * (i & 4095) + 1];
    (void)f.view.footprint_depth({x0, y0, x0 + size, y0 + size}, v, &s);
    benchmark::DoNotOptimize(s.r);
    ++i;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}

}  // namespace

BENCHMARK(BM_TexelRaw);
BENCHMARK(BM_FootprintRaw)->Arg(1)->Arg(4)->Arg(64);
BENCHMARK(BM_EntropyOpenWithChecksums)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EntropyDecodeAll)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TexelEntropy);
BENCHMARK(BM_FootprintEntropy)->Arg(1)->Arg(4)->Arg(64);
BENCHMARK_MAIN();

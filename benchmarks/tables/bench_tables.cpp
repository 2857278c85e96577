// Integral-Radiance tables (tables/, formats/reader/radiance_*): fill throughput (SGGX D
// evaluations per second), fixed-point SAT build, and raw footprint queries per second.
//   build-*/bin/bench_tables                          (all)
//   build-*/bin/bench_tables --benchmark_filter=Fill  (the 256^2 x 32^2 x 8 clusters fill)
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "formats/reader/asset.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "tables/fixed_point_sat.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

using namespace clothbake;
using namespace clothbake::tables;

namespace {

struct Synthetic {
  int n = 0, clusters = 0;
  std::vector<Vec3f> tangent;
  std::vector<float> gap;
  std::vector<uint16_t> yarn;
  std::vector<double> roughness{0.3, 0.04};
  std::vector<uint8_t> labels;
  RadianceInputs inputs() const { return {n, tangent, gap, yarn, roughness, labels, clusters}; }
};

// A weave-like 256^2 map: warp/weft bands with tilted, twisted tangents, gaps, 8 label blocks.
Synthetic synthetic(int n, int clusters) {
  Synthetic s;
  s.n = n;
  s.clusters = clusters;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const bool warp = ((x / 16) + (y / 16)) % 2 == 0;
      const float phase = float(2 * M_PI * (warp ? x : y) / 32.0);
      s.tangent.push_back(warp ? Vec3f{0.3f * std::cos(phase), 1.0f, 0.6f * std::sin(phase)}
                               : Vec3f{1.0f, 0.3f * std::cos(phase), 0.6f * std::sin(phase)});
      s.yarn.push_back(warp ? 0 : 1);
      s.gap.push_back(x % 32 == 31 ? 0.0f : 1.0f);
      s.labels.push_back(uint8_t(((x / 8) * 3 + (y / 8) * 5) % clusters));
    }
  return s;
}

// Args: resolution, bins per side, clusters, samples per bin side. Whole specular fill + SATs.
void BM_FillSpecular(benchmark::State& state) {
  const Synthetic s = synthetic(int(state.range(0)), int(state.range(2)));
  RadianceOptions o;
  o.bins_per_side = int(state.range(1));
  o.samples_per_side = int(state.range(3));
  o.warn_unresolved = false;
  RadianceBuildReport report;
  for (auto _ : state) {
    report = {};
    RadianceTableSet set = build_specular_tables(s.inputs(), o, &report);
    benchmark::DoNotOptimize(set.sat.data());
    state.PauseTiming();
    set = {};  // free outside the timed region
    state.ResumeTiming();
  }
  state.counters["D_evals_per_s"] = benchmark::Counter(
      double(report.d_evaluations) * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["table_GiB"] = double(s.n) * s.n * o.bins_per_side * o.bins_per_side * s.clusters *
                                (report.element_bits / 8) / double(1 << 30);
}
BENCHMARK(BM_FillSpecular)
    ->Args({256, 32, 8, 2})
    ->Args({256, 32, 8, 4})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One bin's bin-averaged D for every texel of a 256^2 map, one thread (the fill's kernel).
void BM_FillKernelOneBin(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const Synthetic s = synthetic(256, 8);
  const HalfVectorBins bins = make_half_vector_bins(32, int(state.range(0)));
  std::vector<float> out(256 * 256);
  int bin = 0;
  for (auto _ : state) {
    radiance_bin_values(reader::RadianceTableKind::Specular, s.inputs(), bins, bin, out.data());
    bin = (bin + 37) % bins.bin_count();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["D_evals_per_s"] = benchmark::Counter(
      double(state.iterations()) * 65536.0 * bins.samples_per_bin(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FillKernelOneBin)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond);

// Fixed-point SAT of one bin: 256^2 texels, 8 interleaved cluster columns, one thread.
void BM_SatBuildOneBin(benchmark::State& state) {
  const int n = 256, columns = 8, bits = int(state.range(0));
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  std::vector<float> v(std::size_t(n) * n);
  std::vector<int16_t> col(v.size());
  std::vector<double> totals(columns, 0.0), units(columns);
  for (std::size_t t = 0; t < v.size(); ++t) {
    v[t] = u(rng);
    col[t] = int16_t(rng() % columns);
    totals[std::size_t(col[t])] += v[t];
  }
  std::vector<std::byte> out(v.size() * columns * std::size_t(bits / 8));
  for (auto _ : state) {
    build_fixed_point_sat(n, v, col, totals, bits, units.data(), out.data());
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(v.size()));
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(out.size()));
}
BENCHMARK(BM_SatBuildOneBin)->Arg(32)->Arg(64)->Unit(benchmark::kMicrosecond);

// A 256^2 table set of 16^2 bins and 8 clusters (512 MiB) in a memory asset, built once.
struct QueryFixture {
  std::vector<std::byte> bytes;
  reader::Asset asset;
  reader::RawRadianceTables tables;
};
QueryFixture& query_fixture() {
  static std::unique_ptr<QueryFixture> f = [] {
    auto q = std::make_unique<QueryFixture>();
    const Synthetic s = synthetic(256, 8);
    RadianceOptions o;
    o.bins_per_side = 16;
    o.samples_per_side = 2;
    o.warn_unresolved = false;
    auto sections = radiance_sections(build_specular_tables(s.inputs(), o));
    q->bytes = formats::serialize_asset(sections);
    sections.clear();
    if (!q->asset.open_memory(q->bytes.data(), q->bytes.size()).ok()) std::abort();
    if (!q->tables.open(q->asset, reader::RadianceTableKind::Specular).ok()) std::abort();
    return q;
  }();
  return *f;
}

struct Query {
  reader::Footprint rect;
  double h[3];
};

// Args: 0 random footprints (1..600 texels wide, anywhere, random h); 1 coherent (a scanline of
// 4 x 4 footprints, one texel apart, h turning slowly).
std::vector<Query> make_queries(int pattern) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Query> out(4096);
  for (std::size_t i = 0; i < out.size(); ++i) {
    Query& q = out[i];
    if (pattern == 0) {
      const double w = std::pow(600.0, u(rng)), h = std::pow(600.0, u(rng));
      q.rect = {512 * u(rng) - 256, 512 * u(rng) - 256, 0, 0};
      q.rect.x1 = q.rect.x0 + w;
      q.rect.y1 = q.rect.y0 + h;
      const double phi = 2 * M_PI * u(rng), z = u(rng), r = std::sqrt(1 - z * z);
      q.h[0] = r * std::cos(phi);
      q.h[1] = r * std::sin(phi);
      q.h[2] = z;
    } else {
      const double x = double(i % 256), y = double(i / 256) * 3.0 + 0.37;
      q.rect = {x + 0.25, y, x + 4.25, y + 4.0};
      const double phi = 0.3 + 1e-3 * double(i);
      q.h[0] = 0.3 * std::cos(phi);
      q.h[1] = 0.3 * std::sin(phi);
      q.h[2] = 0.9;
    }
  }
  return out;
}

// Args: pattern (0 random, 1 coherent), all clusters (0 one cluster, 1 all eight). One thread.
void BM_QueryRaw(benchmark::State& state) {
  QueryFixture& f = query_fixture();
  const auto queries = make_queries(int(state.range(0)));
  const bool all = state.range(1) != 0;
  double out[8];
  std::size_t i = 0;
  for (auto _ : state) {
    const Query& q = queries[i++ & 4095];
    if (all)
      f.tables.try_query_all(q.rect, q.h, out);
    else
      f.tables.try_query(q.rect, q.h, uint32_t(i & 7), out);
    benchmark::DoNotOptimize(out[0]);
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.SetLabel(std::string(state.range(0) ? "coherent" : "random") +
                 (all ? ", all 8 clusters" : ", one cluster"));
}
BENCHMARK(BM_QueryRaw)->ArgsProduct({{0, 1}, {0, 1}});

}  // namespace

namespace {

// The pieces of a query: bin weights (direction -> 4 bins) and the footprint plan.
void BM_QueryPartBinWeights(benchmark::State& state) {
  const auto queries = make_queries(0);
  std::size_t i = 0;
  reader::BinWeights w;
  for (auto _ : state) {
    reader::radiance_bin_weights(32, queries[i++ & 4095].h, &w);
    benchmark::DoNotOptimize(w);
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_QueryPartBinWeights);

// The same direction -> 4 bins lookup through the exact inverse (DirectionGrid::bilinear: atan2
// and an extra square root), which the radiance queries used before bilinear_fast: what the
// polynomial atan saves per query, measured in the same run.
void BM_QueryPartBinWeightsExactAtan2(benchmark::State& state) {
  const auto queries = make_queries(0);
  const model::DirectionGrid<double> grid{32, 0.0};
  std::size_t i = 0;
  for (auto _ : state) {
    const double* h = queries[i++ & 4095].h;
    auto w = grid.bilinear(model::fold_to_upper_hemisphere(model::Vec3d(h[0], h[1], h[2])));
    benchmark::DoNotOptimize(w);
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_QueryPartBinWeightsExactAtan2);

// The fast lookup alone (model::DirectionGrid::bilinear_fast), for the same directions.
void BM_QueryPartBilinearFast(benchmark::State& state) {
  const auto queries = make_queries(0);
  const model::DirectionGrid<double> grid{32, 0.0};
  std::size_t i = 0;
  for (auto _ : state) {
    const double* h = queries[i++ & 4095].h;
    auto w = grid.bilinear_fast(model::fold_to_upper_hemisphere(model::Vec3d(h[0], h[1], h[2])));
    benchmark::DoNotOptimize(w);
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_QueryPartBilinearFast);

void BM_QueryHot(benchmark::State& state) {
  QueryFixture& f = query_fixture();
  const reader::Footprint r{10.25, 20.5, 14.25, 24.0};
  const double h[3] = {0.1, 0.2, 0.9};
  double out[8];
  for (auto _ : state) {
    if (state.range(0))
      f.tables.try_query_all(r, h, out);
    else
      f.tables.try_query(r, h, 3, out);
    benchmark::DoNotOptimize(out[0]);
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_QueryHot)->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();

// Compression of the specular tables of an example fabric at the default size (256^2 texels,
// 32^2 bins, 8 stand-in clusters) with the default settings, and single-thread footprint queries
// (all clusters, pixel-like footprints of 1..16 texels, random half vectors) on the compressed
// tables against the raw fixed-point tables of the same data.
//
//   bench_compress [--benchmark_filter=...]     environment: CLOTHBAKE_BENCH_FABRIC (satin.toml),
//                                               CLOTHBAKE_BENCH_RESOLUTION (256)
// Targets (docs/compression.md): compression <= 10 s wall and <= 4 GiB for one lobe; compressed
// queries >= 2.5 M/s on one core and at most 2x the cost of raw ones.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "compress/compress_settings.hpp"
#include "compress/compressed_set.hpp"
#include "compress/cpca.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/splitmix64.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::compress {
namespace {

struct Data {
  Fabric fabric;
  std::vector<uint8_t> labels;
  tables::FabricRadianceInputs inputs;
  DirectionalTexels texels;
};

Data& data() {
  static std::unique_ptr<Data> d = [] {
    auto d = std::make_unique<Data>();
    const char* fabric = std::getenv("CLOTHBAKE_BENCH_FABRIC");
    const char* res = std::getenv("CLOTHBAKE_BENCH_RESOLUTION");
    LoadOptions lo;
    lo.resolution = res ? std::atoi(res) : 256;
    d->fabric = load_fabric_description(std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/" +
                                            (fabric ? fabric : "satin.toml"),
                                        lo)
                    .fabric;
    const auto& m = d->fabric.maps;
    for (std::size_t t = 0; t < m.texel_count(); ++t)  // 8 stand-in clusters
      d->labels.push_back(uint8_t(4 * (m.yarn_id[t] % 2) + 2 * (m.tangent[t][2] > 0) +
                                  (m.tangent[t][0] * m.tangent[t][1] > 0)));
    d->inputs = tables::radiance_inputs(d->fabric, d->labels, 8);
    d->texels = directional_texels(reader::RadianceTableKind::Specular, d->inputs.view, 32);
    return d;
  }();
  return *d;
}

void BM_CompressDefault(benchmark::State& state) {
  const Data& d = data();
  CompressionStats stats;
  for (auto _ : state) {
    const CompressedTableSet set = compress_tables(d.texels, CompressSettings{}.cpca(), &stats);
    benchmark::DoNotOptimize(set.coefficients.data());
  }
  state.counters["ratio"] = stats.ratio();
  state.counters["images"] = stats.images;
  state.counters["texel_error"] = stats.error;
}
BENCHMARK(BM_CompressDefault)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

struct Queries {
  std::vector<reader::Footprint> rects;
  std::vector<std::array<double, 3>> hs;
};
const Queries& queries() {
  static Queries q = [] {
    Queries q;
    model::SplitMix64 rng(7);
    const double n = data().texels.resolution;
    for (int i = 0; i < 65536; ++i) {
      const double x0 = rng.uniform() * n, y0 = rng.uniform() * n, s = 1 + 15 * rng.uniform();
      q.rects.push_back({x0, y0, x0 + s, y0 + s});
      const double ct = std::max(1e-3, rng.uniform()), phi = 6.283185307 * rng.uniform();
      q.hs.push_back(
          {std::sqrt(1 - ct * ct) * std::cos(phi), std::sqrt(1 - ct * ct) * std::sin(phi), ct});
    }
    return q;
  }();
  return q;
}

// Coherent queries: a scanline of 4 x 4 footprints one texel apart with a slowly turning h (as
// neighbouring pixels ask), the pattern bench_tables' BM_QueryRaw/1/* uses.
const Queries& coherent_queries() {
  static Queries q = [] {
    Queries q;
    const uint32_t n = data().texels.resolution;
    for (int i = 0; i < 65536; ++i) {
      const double x = double(uint32_t(i) % n), y = double(uint32_t(i) / n % n) + 0.37;
      q.rects.push_back({x + 0.25, y, x + 4.25, y + 4.0});
      const double phi = 0.3 + 1e-3 * double(i);
      q.hs.push_back({0.3 * std::cos(phi), 0.3 * std::sin(phi), 0.9});
    }
    return q;
  }();
  return q;
}

// range(0): 0 random footprints (1-16 texels, anywhere), 1 coherent; range(1): 0 every cluster
// (query_all), 1 one cluster (try_query, cycling through them).
void run_queries(benchmark::State& state, const reader::RadianceTables& t) {
  const Queries& q = state.range(0) ? coherent_queries() : queries();
  if (state.range(1)) {
    double out = 0;
    std::size_t i = 0;
    for (auto _ : state) {
      t.try_query(q.rects[i], q.hs[i].data(), uint32_t(i % t.cluster_count()), &out);
      benchmark::DoNotOptimize(out);
      i = (i + 1) & 65535;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
    state.SetLabel(std::string(state.range(0) ? "coherent" : "random") + ", one cluster");
    return;
  }
  std::vector<double> out(t.cluster_count());
  std::size_t i = 0;
  for (auto _ : state) {
    t.try_query_all(q.rects[i], q.hs[i].data(), out.data());
    benchmark::DoNotOptimize(out.data());
    i = (i + 1) & 65535;
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.SetLabel(std::string(state.range(0) ? "coherent" : "random") + ", all clusters");
}

void BM_QueryCompressed(benchmark::State& state) {
  static std::vector<std::byte> bytes = formats::serialize_asset(
      compressed_sections(compress_tables(data().texels, CompressSettings{}.cpca())));
  reader::Asset asset;
  reader::CompressedRadianceTables t;
  if (!asset.open_memory(bytes.data(), bytes.size()).ok() ||
      !t.open(asset, reader::RadianceTableKind::Specular).ok()) {
    state.SkipWithError("cannot open");
    return;
  }
  run_queries(state, t);
  state.counters["images"] = t.image_count();
}
BENCHMARK(BM_QueryCompressed)->ArgsProduct({{0, 1}, {0, 1}});

void BM_QueryRaw(benchmark::State& state) {
  static std::vector<std::byte> bytes = [] {
    tables::RadianceOptions o;
    o.warn_unresolved = false;
    auto sections = tables::radiance_sections(tables::build_specular_tables(data().inputs.view, o));
    return formats::serialize_asset(sections);
  }();
  reader::Asset asset;
  reader::RawRadianceTables t;
  if (!asset.open_memory(bytes.data(), bytes.size()).ok() ||
      !t.open(asset, reader::RadianceTableKind::Specular).ok()) {
    state.SkipWithError("cannot open");
    return;
  }
  run_queries(state, t);
}
BENCHMARK(BM_QueryRaw)->ArgsProduct({{0, 1}, {0, 1}});

}  // namespace
}  // namespace clothbake::compress

BENCHMARK_MAIN();

// bench_capi ASSET.cbk [google-benchmark options]: what a renderer pays to open an asset through
// the C interface, validated (the default) and trusted (CB_OPEN_TRUSTED), from memory and from a
// file; to create an evaluator; and for one unbiased multi-scale estimate of a one-tile footprint.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "clothbake.h"

namespace {

std::string g_path;
std::vector<char> g_bytes;

void open_memory(benchmark::State& state, uint32_t flags) {
  for (auto _ : state) {
    cb_asset* asset = nullptr;
    if (cb_asset_open_memory(g_bytes.data(), g_bytes.size(), flags, nullptr, &asset, nullptr) !=
        CB_OK)
      state.SkipWithError("open failed");
    cb_asset_close(asset);
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(g_bytes.size()));
}

void BM_OpenMemoryValidated(benchmark::State& state) {
  open_memory(state, 0);
}
void BM_OpenMemoryTrusted(benchmark::State& state) {
  open_memory(state, CB_OPEN_TRUSTED);
}

void open_file(benchmark::State& state, uint32_t flags) {
  for (auto _ : state) {
    cb_asset* asset = nullptr;
    if (cb_asset_open_file(g_path.c_str(), flags, nullptr, &asset, nullptr) != CB_OK)
      state.SkipWithError("open failed");
    cb_asset_close(asset);
  }
}
void BM_OpenFileValidated(benchmark::State& state) {
  open_file(state, 0);
}
void BM_OpenFileTrusted(benchmark::State& state) {
  open_file(state, CB_OPEN_TRUSTED);
}

void BM_EvaluatorCreate(benchmark::State& state) {
  cb_asset* asset = nullptr;
  cb_asset_open_file(g_path.c_str(), CB_OPEN_TRUSTED, nullptr, &asset, nullptr);
  cb_options options;
  cb_options_default(&options);
  for (auto _ : state) {
    cb_evaluator* e = nullptr;
    if (cb_evaluator_create(asset, &options, nullptr, &e, nullptr) != CB_OK)
      state.SkipWithError("create failed");
    cb_evaluator_destroy(e);
  }
  cb_asset_close(asset);
}

void BM_EstimateOneTile(benchmark::State& state) {
  cb_asset* asset = nullptr;
  cb_asset_open_file(g_path.c_str(), CB_OPEN_TRUSTED, nullptr, &asset, nullptr);
  cb_options options;
  cb_options_default(&options);
  cb_evaluator* e = nullptr;
  cb_evaluator_create(asset, &options, nullptr, &e, nullptr);
  const cb_footprint tile = {0.25, 0.5, 1.25, 1.5};
  const double wi[3] = {-0.3, 0.2, 0.9}, wo[3] = {0.1, -0.2, 1.0};
  cb_rng rng;
  cb_rng_seed(&rng, 1);
  double rgb[3];
  for (auto _ : state)
    if (cb_estimate(e, &tile, wi, wo, CB_LOBES_ALL, &rng, rgb, nullptr) != CB_OK)
      state.SkipWithError("estimate failed");
  cb_evaluator_destroy(e);
  cb_asset_close(asset);
}

BENCHMARK(BM_OpenMemoryValidated)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenMemoryTrusted)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenFileValidated)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenFileTrusted)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EvaluatorCreate)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EstimateOneTile)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench_capi ASSET.cbk [benchmark options]\n");
    return 1;
  }
  g_path = argv[1];
  std::ifstream in(g_path, std::ios::binary);
  g_bytes.assign(std::istreambuf_iterator<char>(in), {});
  if (g_bytes.empty()) {
    std::fprintf(stderr, "%s: cannot read\n", argv[1]);
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}

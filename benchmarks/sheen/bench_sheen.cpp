// Speed of the sheen layer: what a renderer pays per shading call (model/sheen.hpp) and what the
// fit pays (sheen/: one simulated path, one LTC objective evaluation). Figures in
// docs/performance.md and docs/sheen.md.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "model/sheen.hpp"
#include "sheen/ltc_fit.hpp"
#include "sheen/rng.hpp"
#include "sheen/sheen_layer.hpp"

namespace {

using namespace clothbake;

template <class T>
struct Inputs {
  std::vector<model::Vec3<T>> wi, wo;
  std::vector<T> roughness, u1, u2;
  explicit Inputs(int n) {
    sheen::Rng rng(1, 0);
    auto dir = [&] {
      const double z = 0.01 + 0.99 * rng.uniform(), phi = 6.283185307 * rng.uniform();
      const double s = std::sqrt(1 - z * z);
      return model::Vec3<T>(T(s * std::cos(phi)), T(s * std::sin(phi)), T(z));
    };
    for (int k = 0; k < n; ++k) {
      wi.push_back(dir());
      wo.push_back(dir());
      roughness.push_back(T(rng.uniform()));
      u1.push_back(T(rng.uniform()));
      u2.push_back(T(rng.uniform()));
    }
  }
};

constexpr int kBatch = 4096;

template <class T>
void BM_SheenEval(benchmark::State& state) {
  const Inputs<T> in(kBatch);
  for (auto _ : state)
    for (int k = 0; k < kBatch; ++k)
      benchmark::DoNotOptimize(model::sheen_eval(in.wi[k], in.wo[k], in.roughness[k]));
  state.SetItemsProcessed(state.iterations() * kBatch);
}

template <class T>
void BM_SheenPdf(benchmark::State& state) {
  const Inputs<T> in(kBatch);
  for (auto _ : state)
    for (int k = 0; k < kBatch; ++k)
      benchmark::DoNotOptimize(model::sheen_pdf(in.wi[k], in.wo[k], in.roughness[k]));
  state.SetItemsProcessed(state.iterations() * kBatch);
}

template <class T>
void BM_SheenSample(benchmark::State& state) {
  const Inputs<T> in(kBatch);
  for (auto _ : state)
    for (int k = 0; k < kBatch; ++k)
      benchmark::DoNotOptimize(model::sheen_sample(in.wo[k], in.roughness[k], in.u1[k], in.u2[k]));
  state.SetItemsProcessed(state.iterations() * kBatch);
}

template <class T>
void BM_SheenAlbedo(benchmark::State& state) {
  const Inputs<T> in(kBatch);
  for (auto _ : state)
    for (int k = 0; k < kBatch; ++k)
      benchmark::DoNotOptimize(model::sheen_albedo(in.wo[k].z, in.roughness[k]));
  state.SetItemsProcessed(state.iterations() * kBatch);
}

BENCHMARK_TEMPLATE(BM_SheenEval, float);
BENCHMARK_TEMPLATE(BM_SheenEval, double);
BENCHMARK_TEMPLATE(BM_SheenPdf, float);
BENCHMARK_TEMPLATE(BM_SheenSample, float);
BENCHMARK_TEMPLATE(BM_SheenSample, double);
BENCHMARK_TEMPLATE(BM_SheenAlbedo, float);

// Simulated light paths per second through the layer, at (cos theta_o, roughness) = (arg0 / 100,
// arg1 / 100): a typical node and a grazing, smooth one (long random walks).
void BM_LayerPaths(benchmark::State& state) {
  const double mu = state.range(0) / 100.0, roughness = state.range(1) / 100.0;
  sheen::LayerSimulationSettings s;
  s.paths = 20000;
  uint64_t stream = 0;
  for (auto _ : state) {
    s.stream = stream++;
    benchmark::DoNotOptimize(sheen::simulate_sheen_layer(mu, roughness, s).reflected);
  }
  state.SetItemsProcessed(state.iterations() * int64_t(s.paths));
}
BENCHMARK(BM_LayerPaths)->Args({50, 50})->Args({3, 10})->Unit(benchmark::kMillisecond);

// One evaluation of the LTC fit objective's quadrature (32 x 32 bins, 3 x 3 nodes each).
void BM_LtcBinProbabilities(benchmark::State& state) {
  const sheen::LtcBinQuadrature quadrature(sheen::ExitBinning{32, 32});
  std::vector<double> p;
  for (auto _ : state) {
    quadrature.bin_probabilities(0.3, -0.1, p);
    benchmark::DoNotOptimize(p.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LtcBinProbabilities)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

// Speed of the cloth BSDF library (model/): D of the fibre-like SGGX distribution, scalar and
// batched (the Integral-Radiance table fill, paper Eq. 11), each lobe, the full BSDF of Eq. 3-4,
// its mixture pdf and its sampler. Items per second = evaluations per second (one core).
//
//   build-*/bin/bench_model --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "model/cloth_bsdf.hpp"
#include "model/sggx.hpp"
#include "model/sggx_batch.hpp"

namespace {

namespace m = clothbake::model;

template <class T>
std::vector<m::Vec3<T>> random_directions(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<m::Vec3<T>> out;
  out.reserve(n);
  while (out.size() < n) {
    m::Vec3d v{g(rng), g(rng), g(rng)};
    const double l = m::length(v);
    if (l > 1e-6) out.push_back(m::Vec3<T>(v / l));
  }
  return out;
}

template <class T>
m::TexelParams<T> bench_params() {
  m::TexelParams<T> p;
  p.tangent = {T(0.8), T(0.2), T(0.3)};
  p.roughness = T(0.2);
  p.optical_thickness = T(2);
  p.specular_albedo = m::Rgb<T>(T(0.7));
  p.diffuse_reflectance = m::Rgb<T>(T(0.1));
  p.diffuse_transmittance = m::Rgb<T>(T(0.1));
  p.gap = T(0.9);
  p.sheen_color = m::Rgb<T>(T(0.5));
  p.sheen_roughness = T(0.5);
  return p;
}

constexpr std::size_t kDirs = 4096;

// Scalar D of one texel over unit half vectors (FibreSggx::D_unit), and D of unnormalised ones.
template <class T>
void BM_D_scalar(benchmark::State& state) {
  const auto d = m::FibreSggx<T>::make({T(0.8), T(0.2), T(0.3)}, T(0.2));
  const auto h = random_directions<T>(kDirs, 1);
  for (auto _ : state)
    for (const auto& v : h)
      benchmark::DoNotOptimize(d.D_unit(v));
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kDirs));
}
template <class T>
void BM_D_scalar_unnormalised(benchmark::State& state) {
  const auto d = m::FibreSggx<T>::make({T(0.8), T(0.2), T(0.3)}, T(0.2));
  auto h = random_directions<T>(kDirs, 1);
  for (auto& v : h)
    v = v * T(1.7);
  for (auto _ : state)
    for (const auto& v : h)
      benchmark::DoNotOptimize(d.D(v));
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kDirs));
}

// Batched D over texels for one half vector (the table fill: one bin, a 256 x 256 tile).
template <class T>
void BM_D_batch_texels(benchmark::State& state) {
  const std::size_t n = std::size_t(state.range(0));
  const auto tangents = random_directions<T>(n, 2);
  m::FibreSggxBatch<T> batch;
  batch.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    batch.set(i, m::FibreSggx<T>::make(tangents[i], T(0.05) + T(0.9) * T(i % 17) / T(17)));
  std::vector<T> out(n);
  const m::Vec3<T> h = m::normalize(m::Vec3<T>{T(0.2), T(0.3), T(0.9)});
  for (auto _ : state) {
    m::sggx_d_over_texels(batch, h, out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(n));
}

// Batched D over half vectors for one texel.
template <class T>
void BM_D_batch_directions(benchmark::State& state) {
  const auto d = m::FibreSggx<T>::make({T(0.8), T(0.2), T(0.3)}, T(0.2));
  const auto h = random_directions<T>(kDirs, 3);
  std::vector<T> hx(kDirs), hy(kDirs), hz(kDirs), out(kDirs);
  for (std::size_t j = 0; j < kDirs; ++j)
    hx[j] = h[j].x, hy[j] = h[j].y, hz[j] = h[j].z;
  for (auto _ : state) {
    m::sggx_d_over_directions(d, kDirs, hx.data(), hy.data(), hz.data(), out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kDirs));
}

// One lobe over pairs of random directions.
enum class Which { SpecularReflection, SpecularTransmission, Diffuse, Sheen, Full, Pdf };

template <class T, Which W>
void BM_lobe(benchmark::State& state) {
  const m::ClothBsdf<T> bsdf(bench_params<T>());
  const auto wi = random_directions<T>(kDirs, 4), wo = random_directions<T>(kDirs, 5);
  const auto& d = bsdf.sggx();
  const T thickness = bsdf.optical_thickness();
  for (auto _ : state)
    for (std::size_t k = 0; k < kDirs; ++k) {
      const auto& i = wi[k];
      const auto& o = wo[k];
      if constexpr (W == Which::SpecularReflection)
        benchmark::DoNotOptimize(m::spongecake_reflection(d, thickness, i, o));
      else if constexpr (W == Which::SpecularTransmission)
        benchmark::DoNotOptimize(m::spongecake_transmission(d, thickness, i, o));
      else if constexpr (W == Which::Diffuse)
        benchmark::DoNotOptimize(m::lambert_reflection(i, o) + m::lambert_transmission(i, o));
      else if constexpr (W == Which::Sheen)
        benchmark::DoNotOptimize(m::sheen_eval(i, o, T(0.5)));
      else if constexpr (W == Which::Full)
        benchmark::DoNotOptimize(bsdf.eval(i, o));
      else
        benchmark::DoNotOptimize(bsdf.pdf(i, o));
    }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kDirs));
}

template <class T>
void BM_sample(benchmark::State& state) {
  const m::ClothBsdf<T> bsdf(bench_params<T>());
  const auto wo = random_directions<T>(kDirs, 6);
  std::mt19937 rng(7);
  std::uniform_real_distribution<T> uni(T(0), T(1));
  std::vector<T> u(3 * kDirs);
  for (auto& x : u)
    x = uni(rng);
  for (auto _ : state)
    for (std::size_t k = 0; k < kDirs; ++k)
      benchmark::DoNotOptimize(bsdf.sample(wo[k], u[3 * k], u[3 * k + 1], u[3 * k + 2]));
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kDirs));
}

BENCHMARK(BM_D_scalar<float>);
BENCHMARK(BM_D_scalar<double>);
BENCHMARK(BM_D_scalar_unnormalised<float>);
BENCHMARK(BM_D_batch_texels<float>)->Arg(256 * 256);
BENCHMARK(BM_D_batch_texels<double>)->Arg(256 * 256);
BENCHMARK(BM_D_batch_directions<float>);
BENCHMARK(BM_D_batch_directions<double>);
BENCHMARK(BM_lobe<float, Which::SpecularReflection>)->Name("BM_specular_reflection<float>");
BENCHMARK(BM_lobe<double, Which::SpecularReflection>)->Name("BM_specular_reflection<double>");
BENCHMARK(BM_lobe<float, Which::SpecularTransmission>)->Name("BM_specular_transmission<float>");
BENCHMARK(BM_lobe<double, Which::SpecularTransmission>)->Name("BM_specular_transmission<double>");
BENCHMARK(BM_lobe<float, Which::Diffuse>)->Name("BM_diffuse<float>");
BENCHMARK(BM_lobe<float, Which::Sheen>)->Name("BM_sheen<float>");
BENCHMARK(BM_lobe<float, Which::Full>)->Name("BM_full_bsdf<float>");
BENCHMARK(BM_lobe<double, Which::Full>)->Name("BM_full_bsdf<double>");
BENCHMARK(BM_lobe<float, Which::Pdf>)->Name("BM_pdf<float>");
BENCHMARK(BM_sample<float>);
BENCHMARK(BM_sample<double>);

}  // namespace

BENCHMARK_MAIN();

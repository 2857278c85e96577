// Directional albedo of one lobe of the cloth BSDF by importance sampling:
//   A(wi) = ∫_H f_sel(wi, wo) |cos θ_o| dω_o
// over one hemisphere H of wo, where f_sel is a caller-chosen part of f(wi, wo) (one lobe, or the
// total of the non-delta lobes). The quantity `clothbake bsdf --slice` reports as `integral_cos`.
//
// Why not a pixel sum: at roughness ≤ 1e-3 the specular lobe is narrower than a pixel of any
// practical slice image, so the midpoint sum over an N² equal-area grid misses or overcounts it
// (twill fibre, roughness 1e-3, cos θ_i = 0.045: 0.180 at 256², 0.226 at 1024², 0.216 at 4096²).
// The BSDF's own sampler follows the lobe at every roughness.
//
// Estimator (docs/model.md, "Lobe integrals"): wo is drawn from the defensive mixture
//   p(wo) = (1 − ε) · pdf_bsdf(wo | wi) + ε · 1/(2π) on H,   ε = kDefensiveFraction,
// where pdf_bsdf(wo | wi) = ClothBsdf::pdf(wo, wi) is the density of ClothBsdf::sample(wi, ...)
// (its delta draws and the other hemisphere contribute 0). The uniform part keeps p > 0 wherever
// f_sel > 0, so the estimate mean of f_sel |cos θ_o| / p is unbiased even where the sampler's
// density misses part of the lobe (e.g. a lobe that is not reciprocal). Random numbers: SplitMix64
// from `seed`, so the result is reproducible.
//
// C++17, header-only, standard library only. Safe on any finite inputs; samples must be ≥ 2.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "model/cloth_bsdf.hpp"
#include "model/rgb.hpp"
#include "model/splitmix64.hpp"
#include "model/vec.hpp"

namespace clothbake::model {

inline constexpr double kDefensiveFraction = 0.1;

struct LobeIntegral {
  Rgb<double> mean;            // the estimate of A(wi), per channel
  Rgb<double> standard_error;  // its standard error (sample standard deviation / √samples)
  uint64_t samples = 0;
};

// `select(const LobeValues<double>&) -> Rgb<double>` picks the integrand's part of f (e.g. one
// lobe). `upper`: H is z > 0 (else z < 0). `visibility` is passed to ClothBsdf::eval as V.
template <class Select>
LobeIntegral lobe_integral_cos(const ClothBsdf<double>& bsdf, const Vec3<double>& wi,
                               double visibility, const Select& select, bool upper,
                               uint64_t samples, uint64_t seed) {
  constexpr double kPi = 3.14159265358979323846;
  const double uniform_density = 1.0 / (2.0 * kPi);
  SplitMix64 rng(seed);
  Rgb<double> sum, sum_sq;
  for (uint64_t i = 0; i < samples; ++i) {
    const double u_pick = rng.uniform(), u_lobe = rng.uniform();
    const double u1 = rng.uniform(), u2 = rng.uniform();
    Vec3<double> wo;
    if (u_pick < kDefensiveFraction) {
      const double z = u1, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = 2.0 * kPi * u2;
      wo = {r * std::cos(phi), r * std::sin(phi), upper ? z : -z};
    } else {
      const BsdfSample<double> s = bsdf.sample(wi, u_lobe, u1, u2);
      if (!s.valid || s.is_delta) continue;  // contributes 0
      wo = s.wi;
    }
    if (!((wo.z > 0.0) == upper) || wo.z == 0.0) continue;  // outside H: f_sel = 0 there
    const double density =
        (1.0 - kDefensiveFraction) * bsdf.pdf(wo, wi) + kDefensiveFraction * uniform_density;
    const Rgb<double> f = select(bsdf.eval(wi, wo, visibility));
    const Rgb<double> value = f * (std::abs(wo.z) / density);
    sum += value;
    sum_sq += value * value;
  }
  LobeIntegral out;
  out.samples = samples;
  const double n = double(samples);
  out.mean = sum / n;
  for (int c = 0; c < 3; ++c) {
    const double mean = out.mean[c];
    const double variance = std::max(0.0, (sum_sq[c] / n - mean * mean) * n / (n - 1.0));
    const double se = std::sqrt(variance / n);
    if (c == 0) out.standard_error.r = se;
    if (c == 1) out.standard_error.g = se;
    if (c == 2) out.standard_error.b = se;
  }
  return out;
}

}  // namespace clothbake::model

// The full local cloth BSDF of paper Eq. 3-4 at one texel, every lobe separately, and its
// importance sampling (paper Sec. 5.1).
//
//   f(x, i, o) = V(x', i) f^(x', i, o)                                                      (Eq. 3)
//   f^ = f_sheen + T_sheen I (f_rs + f_rd) + T_sheen I (f_ts + f_td) + T_sheen (1 - I) f_delta (Eq.
//   4)
//
// Lobes (docs/model.md has every formula and convention):
//   specular_reflection / specular_transmission : alpha * SpongeCake f_r / f_t of a fibre-like SGGX
//                                                  slab (model/spongecake.hpp, model/sggx.hpp);
//   diffuse_reflection / diffuse_transmission   : R_d / pi, T_d / pi (model/diffuse.hpp);
//   sheen                                       : colour * sheen_eval (model/sheen.hpp, LTC);
//   delta_transmission                          : T_sheen (1 - I) delta(i + o) / |i_z| through
//   gaps.
// T_sheen = 1 - colour * R(|o_z|) per channel, R the sheen layer's directional albedo towards the
// viewer (the energy the sheen layer lets through to the layers below).
//
// Conventions: i towards the light, o towards the viewer, unit vectors in the local frame (z =
// macro normal). Values are per steradian without the cosine factor |i_z| (Eq. 5 applies it). The
// model is two-sided: seen from below (o_z < 0) the cloth is its mirror image through the surface
// plane (every lobe uses |z|; sheen is applied to the mirrored directions). Reflection means i_z
// o_z > 0, transmission i_z o_z < 0; directions with z = 0 get 0.
//
// Sampling (Sec. 5.1): given o, the attenuation A(l) of each technique is computed, a technique is
// chosen with probability p_a(l) = A(l) / sum A, a direction i is drawn from its density p_l, and
//   weight      = f^(i, o) |i_z| / pdf(i, o),  pdf = sum_l p_a(l) p_l(i)   (one-sample MIS,
//                                                                          balance heuristic),
//   lobe_weight = f_l(i, o) |i_z| / (p_a(l) p_l(i))                        (the paper's w).
// Both are unbiased estimators of the integral of f^ |i_z| against a unit radiance; `weight` has
// lower variance and is what a renderer should use. The techniques are: sheen (LTC), specular
// (SGGX visible normals reflected about o: one density covers both specular lobes, the direction
// lands on either side), diffuse reflection and diffuse transmission (cosine), delta (i = -o).
// The visibility V(x', i) of Eq. 3 depends on the sampled i: multiply the weight by it afterwards.
//
// Header-only, C++17, standard library only, float or double. Construction sanitises the
// parameters (clamps to the documented ranges, NaN to defaults) so that every output is finite and
// >= 0 for any finite unit directions (safe on untrusted values); validate_texel_params reports
// out-of-range values for callers that must reject them.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "model/diffuse.hpp"
#include "model/parameter_ranges.hpp"
#include "model/rgb.hpp"
#include "model/sggx.hpp"
#include "model/sheen.hpp"
#include "model/spongecake.hpp"
#include "model/vec.hpp"

namespace clothbake::model {

// Per-texel parameters of the BSDF (after parallax: the texel at x').
template <class T>
struct TexelParams {
  Vec3<T> tangent{T(1), T(0), T(0)};     // fibre tangent, local frame (normalised by the BSDF)
  T roughness = T(0.3);                  // SGGX fibre roughness sigma in [1e-4, 1]
  T optical_thickness = T(2);            // SpongeCake slab optical thickness T in [0, inf]
  Rgb<T> specular_albedo{T(0.8)};        // single-scattering albedo alpha, [0, 1]
  Rgb<T> diffuse_reflectance{T(0.1)};    // R_d, [0, 1]
  Rgb<T> diffuse_transmittance{T(0.1)};  // T_d, [0, 1]
  T gap = T(1);                          // I(x) in [0, 1]: 1 = yarn, 0 = gap (delta transmission)
  Rgb<T> sheen_color{T(0)};              // sheen colour in [0, 1]; zero disables sheen
  T sheen_roughness = T(0.5);            // sheen roughness in [1e-4, 1]
  // Which sheen table (model/sheen.hpp): the published one by default, as renderers ship it.
  SheenConvention sheen_convention = SheenConvention::Published;
};

#ifndef CLOTHBAKE_SINGLE_FILE  // the tools', not shading's (the single file leaves it out)
// max over channels of alpha + R_d + T_d - 1: <= 0 guarantees energy conservation of f^ (the
// single-scattering albedo of the specular lobes never exceeds alpha).
template <class T>
inline T energy_excess(const TexelParams<T>& p) {
  const Rgb<T> sum = p.specular_albedo + p.diffuse_reflectance + p.diffuse_transmittance;
  return sum.max_component() - T(1);
}
#endif

enum class Lobe : int {
  SpecularReflection = 0,
  SpecularTransmission,
  DiffuseReflection,
  DiffuseTransmission,
  DeltaTransmission,
  Sheen,
};
inline constexpr int kLobeCount = 6;

#ifndef CLOTHBAKE_SINGLE_FILE  // the tools', not shading's (the single file leaves it out)
inline const char* lobe_name(Lobe lobe) {
  switch (lobe) {
    case Lobe::SpecularReflection:
      return "specular_reflection";
    case Lobe::SpecularTransmission:
      return "specular_transmission";
    case Lobe::DiffuseReflection:
      return "diffuse_reflection";
    case Lobe::DiffuseTransmission:
      return "diffuse_transmission";
    case Lobe::DeltaTransmission:
      return "delta_transmission";
    case Lobe::Sheen:
      return "sheen";
  }
  return "unknown";
}
#endif

// Every lobe of f = V f^ at one (i, o), RGB, per steradian, no cosine factor.
template <class T>
struct LobeValues {
  Rgb<T> specular_reflection, specular_transmission, diffuse_reflection, diffuse_transmission,
      sheen;
  // The weight W of the Dirac term W delta(i + o) / |i_z| (dimensionless, the gap's transmittance
  // V T_sheen (1 - I)); it is a distribution, so it is reported apart and not part of `total`.
  Rgb<T> delta_transmission;
  Rgb<T> total;  // sum of the five non-delta lobes

  Rgb<T> operator[](Lobe lobe) const {
    switch (lobe) {
      case Lobe::SpecularReflection:
        return specular_reflection;
      case Lobe::SpecularTransmission:
        return specular_transmission;
      case Lobe::DiffuseReflection:
        return diffuse_reflection;
      case Lobe::DiffuseTransmission:
        return diffuse_transmission;
      case Lobe::DeltaTransmission:
        return delta_transmission;
      case Lobe::Sheen:
        return sheen;
    }
    return {};
  }
};

// Sampling techniques of the one-sample mixture (Sec. 5.1).
enum class Technique : int { Sheen = 0, Specular, DiffuseReflection, DiffuseTransmission, Delta };
inline constexpr int kTechniqueCount = 5;

#ifndef CLOTHBAKE_SINGLE_FILE  // the tools', not shading's (the single file leaves it out)
inline const char* technique_name(Technique t) {
  switch (t) {
    case Technique::Sheen:
      return "sheen";
    case Technique::Specular:
      return "specular";
    case Technique::DiffuseReflection:
      return "diffuse_reflection";
    case Technique::DiffuseTransmission:
      return "diffuse_transmission";
    case Technique::Delta:
      return "delta_transmission";
  }
  return "unknown";
}
#endif

// Selection probabilities p_a of the techniques for one o (sum to 1, or all 0 if f^ = 0).
template <class T>
struct TechniqueProbabilities {
  T p[kTechniqueCount] = {};
  T operator[](Technique t) const { return p[int(t)]; }
};

template <class T>
struct BsdfSample {
  bool valid = false;     // false: no direction (f^ = 0 for this o, or a degenerate draw)
  bool is_delta = false;  // true: i = -o exactly, from the delta technique
  Vec3<T> wi;             // sampled unit direction towards the light
  Technique technique = Technique::Specular;  // the technique that drew wi
  Lobe lobe = Lobe::SpecularReflection;       // the lobe wi falls in (side and technique)
  // Non-delta: mixture solid-angle density sum_l p_a(l) p_l(wi). Delta: the discrete probability
  // p_a(delta) of choosing the delta technique.
  T pdf = T(0);
  Rgb<T> weight;       // f^ |i_z| / pdf (non-delta), W / p_a(delta) (delta); times V(x', wi)
  Rgb<T> lobe_weight;  // f_l |i_z| / (p_a p_l) of the chosen technique (the paper's w)
};

// The BSDF of one texel with its constants precomputed. Cheap to copy.
template <class T>
class ClothBsdf {
 public:
  explicit ClothBsdf(const TexelParams<T>& params) { set(params); }

  void set(const TexelParams<T>& params) {
    auto clamp01 = [](T v) { return v > T(0) ? (v < T(1) ? v : T(1)) : T(0); };  // NaN -> 0
    auto clamp_rgb = [&](const Rgb<T>& c) {
      return Rgb<T>{clamp01(c.r), clamp01(c.g), clamp01(c.b)};
    };
    sggx_ = FibreSggx<T>::make(params.tangent, params.roughness);
    thickness_ = params.optical_thickness > T(0) ? params.optical_thickness : T(0);
    alpha_ = clamp_rgb(params.specular_albedo);
    diffuse_r_ = clamp_rgb(params.diffuse_reflectance);
    diffuse_t_ = clamp_rgb(params.diffuse_transmittance);
    gap_ = std::isnan(params.gap) ? T(1) : clamp01(params.gap);
    sheen_color_ = clamp_rgb(params.sheen_color);
    sheen_roughness_ = clamp01(params.sheen_roughness);
    sheen_convention_ = params.sheen_convention == SheenConvention::Converged
                            ? SheenConvention::Converged
                            : SheenConvention::Published;
    has_sheen_ = sheen_color_.max_component() > T(0);
  }

  const FibreSggx<T>& sggx() const { return sggx_; }
  T optical_thickness() const { return thickness_; }
  T gap() const { return gap_; }

  // T_sheen = 1 - colour * R(|o_z|), per channel, in [0, 1].
  Rgb<T> sheen_transmittance(const Vec3<T>& wo) const {
    if (!has_sheen_) return Rgb<T>(T(1));
    const T albedo = sheen_albedo(std::abs(wo.z), sheen_roughness_, sheen_convention_);
    return Rgb<T>(T(1)) - sheen_color_ * albedo;
  }

  // Every lobe of f = V f^ at (wi, wo) (unit vectors); visibility V = V(x', wi) in [0, 1].
  LobeValues<T> eval(const Vec3<T>& wi, const Vec3<T>& wo, T visibility = T(1)) const {
    LobeValues<T> out;
    const Rgb<T> t_sheen = sheen_transmittance(wo);
    const Rgb<T> base = t_sheen * (gap_ * visibility);
    const T fr = spongecake_reflection(sggx_, thickness_, wi, wo);
    const T ft = spongecake_transmission(sggx_, thickness_, wi, wo);
    out.specular_reflection = base * alpha_ * fr;
    out.specular_transmission = base * alpha_ * ft;
    out.diffuse_reflection = base * diffuse_r_ * lambert_reflection(wi, wo);
    out.diffuse_transmission = base * diffuse_t_ * lambert_transmission(wi, wo);
    out.sheen = sheen_color_ * (visibility * sheen_value(wi, wo));
    out.delta_transmission = t_sheen * ((T(1) - gap_) * visibility);
    out.total = out.specular_reflection + out.specular_transmission + out.diffuse_reflection +
                out.diffuse_transmission + out.sheen;
    return out;
  }

  // f^ (all non-delta lobes, V = 1) at (wi, wo): the quantity the sampler's weight integrates.
  Rgb<T> eval_total(const Vec3<T>& wi, const Vec3<T>& wo) const { return eval(wi, wo).total; }

  // Attenuations A(l) of the techniques for o (Sec. 5.1), scalar (channel mean), >= 0:
  //   sheen    : mean(colour) R(|o_z|)                   (the sheen layer's albedo),
  //   specular : mean(T_sheen) I mean(alpha) (1 - e^{-T Lambda(o)})
  //              (the fraction of light that interacts with the slab: an upper bound of the
  //              single-scattering albedo of f_rs + f_ts, positive whenever they are),
  //   diffuse  : mean(T_sheen) I mean(R_d), mean(T_sheen) I mean(T_d)   (their exact albedos),
  //   delta    : mean(T_sheen) (1 - I)                    (its exact weight).
  TechniqueProbabilities<T> technique_probabilities(const Vec3<T>& wo) const {
    TechniqueProbabilities<T> a;
    const T t_sheen = sheen_transmittance(wo).mean();
    if (has_sheen_ && wo.z != T(0))
      a.p[int(Technique::Sheen)] =
          sheen_color_.mean() * sheen_albedo(std::abs(wo.z), sheen_roughness_, sheen_convention_);
    if (thickness_ > T(0) && wo.z != T(0)) {
      const T interact = -std::expm1(-thickness_ * spongecake_lambda(sggx_, wo));
      a.p[int(Technique::Specular)] = t_sheen * gap_ * alpha_.mean() * interact;
    }
    if (wo.z != T(0)) {
      a.p[int(Technique::DiffuseReflection)] = t_sheen * gap_ * diffuse_r_.mean();
      a.p[int(Technique::DiffuseTransmission)] = t_sheen * gap_ * diffuse_t_.mean();
    }
    a.p[int(Technique::Delta)] = t_sheen * (T(1) - gap_);
    T sum = T(0);
    for (T v : a.p)
      sum += v;
    if (!(sum > T(0)) || !std::isfinite(sum)) return TechniqueProbabilities<T>{};
    for (T& v : a.p)
      v /= sum;
    return a;
  }

  // Solid-angle density p_l(wi) of one continuous technique (0 for Delta).
  T technique_pdf(Technique technique, const Vec3<T>& wi, const Vec3<T>& wo) const {
    switch (technique) {
      case Technique::Sheen:
        return sheen_density(wi, wo);
      case Technique::Specular:
        return spongecake_sample_pdf(sggx_, wi, wo);
      case Technique::DiffuseReflection:
        return lambert_reflection_pdf(wi, wo);
      case Technique::DiffuseTransmission:
        return lambert_transmission_pdf(wi, wo);
      case Technique::Delta:
        return T(0);
    }
    return T(0);
  }

  // Mixture density of `sample` over the continuous techniques, sum_l p_a(l) p_l(wi) (the delta
  // technique contributes a discrete probability, not a density). Integrates to 1 - p_a(delta).
  T pdf(const Vec3<T>& wi, const Vec3<T>& wo) const {
    return pdf(technique_probabilities(wo), wi, wo);
  }
  T pdf(const TechniqueProbabilities<T>& pa, const Vec3<T>& wi, const Vec3<T>& wo) const {
    T sum = T(0);
    for (int k = 0; k < kTechniqueCount; ++k)
      if (Technique(k) != Technique::Delta && pa.p[k] > T(0))
        sum += pa.p[k] * technique_pdf(Technique(k), wi, wo);
    return sum;
  }

  // Draws wi for wo (unit): u_lobe selects the technique, u1 and u2 drive it (all in [0, 1)).
  BsdfSample<T> sample(const Vec3<T>& wo, T u_lobe, T u1, T u2) const {
    return sample(technique_probabilities(wo), wo, u_lobe, u1, u2);
  }
  // The same with the technique probabilities `pa` (normalised; p_a(l) > 0 only where technique l
  // can draw for wo), whose pdf(pa, wi, wo) is then the density.
  BsdfSample<T> sample(const TechniqueProbabilities<T>& pa, const Vec3<T>& wo, T u_lobe, T u1,
                       T u2) const {
    BsdfSample<T> s;
    // Choose the technique: the first whose cumulative probability exceeds u_lobe.
    int chosen = -1;
    T cumulative = T(0);
    int last_positive = -1;
    for (int k = 0; k < kTechniqueCount; ++k) {
      if (!(pa.p[k] > T(0))) continue;
      last_positive = k;
      cumulative += pa.p[k];
      if (u_lobe < cumulative) {
        chosen = k;
        break;
      }
    }
    if (chosen < 0) chosen = last_positive;  // u_lobe at the top edge or rounding of the sum
    if (chosen < 0) return s;                // f^ = 0 for this o
    const Technique technique = Technique(chosen);
    s.technique = technique;

    if (technique == Technique::Delta) {
      s.valid = true;
      s.is_delta = true;
      s.wi = -wo;
      s.lobe = Lobe::DeltaTransmission;
      s.pdf = pa.p[chosen];
      const Rgb<T> w = sheen_transmittance(wo) * (T(1) - gap_);
      s.weight = w / s.pdf;
      s.lobe_weight = s.weight;
      return s;
    }

    Vec3<T> wi;
    switch (technique) {
      case Technique::Sheen:
        wi = sheen_direction(wo, u1, u2);
        break;
      case Technique::Specular:
        wi = spongecake_sample(sggx_, wo, u1, u2);
        break;
      case Technique::DiffuseReflection:
        wi = lambert_reflection_sample(wo, u1, u2);
        break;
      case Technique::DiffuseTransmission:
        wi = lambert_transmission_sample(wo, u1, u2);
        break;
      case Technique::Delta:
        break;
    }
    if (!(wi.z != T(0)) || !std::isfinite(wi.x + wi.y + wi.z)) return s;  // degenerate draw
    const T mixture = pdf(pa, wi, wo);
    if (!(mixture > T(0))) return s;
    const LobeValues<T> f = eval(wi, wo);
    const T cos_i = std::abs(wi.z);
    s.valid = true;
    s.wi = wi;
    s.pdf = mixture;
    s.weight = f.total * (cos_i / mixture);
    const bool reflect = (wi.z > T(0)) == (wo.z > T(0));
    Rgb<T> f_technique;
    switch (technique) {
      case Technique::Sheen:
        s.lobe = Lobe::Sheen;
        f_technique = f.sheen;
        break;
      case Technique::Specular:
        s.lobe = reflect ? Lobe::SpecularReflection : Lobe::SpecularTransmission;
        f_technique = f.specular_reflection + f.specular_transmission;
        break;
      case Technique::DiffuseReflection:
        s.lobe = Lobe::DiffuseReflection;
        f_technique = f.diffuse_reflection;
        break;
      case Technique::DiffuseTransmission:
        s.lobe = Lobe::DiffuseTransmission;
        f_technique = f.diffuse_transmission;
        break;
      case Technique::Delta:
        break;
    }
    const T p_technique = pa.p[chosen] * technique_pdf(technique, wi, wo);
    s.lobe_weight = p_technique > T(0) ? f_technique * (cos_i / p_technique) : Rgb<T>{};
    return s;
  }

 private:
  // Sheen on the side of o: seen from below, the mirrored configuration.
  static Vec3<T> mirror(const Vec3<T>& w) { return {w.x, w.y, -w.z}; }

  T sheen_value(const Vec3<T>& wi, const Vec3<T>& wo) const {
    if (!has_sheen_) return T(0);
    return wo.z < T(0) ? sheen_eval(mirror(wi), mirror(wo), sheen_roughness_, sheen_convention_)
                       : sheen_eval(wi, wo, sheen_roughness_, sheen_convention_);
  }
  T sheen_density(const Vec3<T>& wi, const Vec3<T>& wo) const {
    return wo.z < T(0) ? sheen_pdf(mirror(wi), mirror(wo), sheen_roughness_, sheen_convention_)
                       : sheen_pdf(wi, wo, sheen_roughness_, sheen_convention_);
  }
  Vec3<T> sheen_direction(const Vec3<T>& wo, T u1, T u2) const {
    return wo.z < T(0)
               ? mirror(sheen_sample(mirror(wo), sheen_roughness_, u1, u2, sheen_convention_))
               : sheen_sample(wo, sheen_roughness_, u1, u2, sheen_convention_);
  }

  FibreSggx<T> sggx_;
  T thickness_ = T(0);
  Rgb<T> alpha_, diffuse_r_, diffuse_t_;
  T gap_ = T(1);
  Rgb<T> sheen_color_;
  T sheen_roughness_ = T(0.5);
  SheenConvention sheen_convention_ = SheenConvention::Published;
  bool has_sheen_ = false;
};

}  // namespace clothbake::model

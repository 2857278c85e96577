// Diffuse reflection f^{r,d} and transmission f^{t,d} of the cloth BSDF (paper Eq. 1 and 4): the
// higher-order scattering inside the yarn, modelled as Lambertian lobes as in SpongeCake's
// multiple-scattering approximation (Wang et al. 2022) and Zhu et al. 2023:
//
//   f^{r,d}(i, o) = R_d / pi   if i_z o_z > 0, else 0,
//   f^{t,d}(i, o) = T_d / pi   if i_z o_z < 0, else 0,
//
// with R_d, T_d the hemispherical reflectance and transmittance (the fraction of light scattered
// diffusely up or down). Both are reciprocal. The albedos are taken as given (not rescaled by the
// specular lobes): the full BSDF conserves energy whenever alpha + R_d + T_d <= 1 per channel
// (docs/model.md), which validate_texel_params reports.
//
// Sampling: cosine-weighted directions on the side of o (reflection) or the opposite side
// (transmission), density |i_z| / pi on that side.
//
// Header-only, C++17, standard library only, float or double; total functions (safe on any input).
#pragma once

#include <algorithm>
#include <cmath>

#include "model/directions.hpp"  // kPi, concentric_square_to_disk
#include "model/vec.hpp"

namespace clothbake::model {

// 1/pi if i and o are strictly on the same side of the surface, else 0 (multiply by R_d).
template <class T>
inline T lambert_reflection(const Vec3<T>& wi, const Vec3<T>& wo) {
  return (wi.z > T(0) && wo.z > T(0)) || (wi.z < T(0) && wo.z < T(0)) ? T(1) / kPi<T> : T(0);
}

// 1/pi if i and o are strictly on opposite sides of the surface, else 0 (multiply by T_d).
template <class T>
inline T lambert_transmission(const Vec3<T>& wi, const Vec3<T>& wo) {
  return (wi.z > T(0) && wo.z < T(0)) || (wi.z < T(0) && wo.z > T(0)) ? T(1) / kPi<T> : T(0);
}

// Cosine-weighted unit direction on the upper hemisphere (Malley's method on the concentric disk),
// u1, u2 in [0, 1]. Density z / pi.
template <class T>
inline Vec3<T> sample_cosine_hemisphere(T u1, T u2) {
  T x, y;
  concentric_square_to_disk(T(2) * u1 - T(1), T(2) * u2 - T(1), x, y);
  const T z = std::sqrt(std::max(T(0), T(1) - x * x - y * y));
  return {x, y, z};
}

// Density of a cosine-weighted direction on the side `upper` (z > 0) or the lower side.
template <class T>
inline T cosine_hemisphere_pdf(const Vec3<T>& w, bool upper) {
  const T z = upper ? w.z : -w.z;
  return z > T(0) ? z / kPi<T> : T(0);
}

// Samples i for the diffuse reflection lobe of o (same side as o), u1, u2 in [0, 1].
template <class T>
inline Vec3<T> lambert_reflection_sample(const Vec3<T>& wo, T u1, T u2) {
  Vec3<T> w = sample_cosine_hemisphere(u1, u2);
  if (wo.z < T(0)) w.z = -w.z;
  return w;
}

// Samples i for the diffuse transmission lobe of o (opposite side to o), u1, u2 in [0, 1].
template <class T>
inline Vec3<T> lambert_transmission_sample(const Vec3<T>& wo, T u1, T u2) {
  Vec3<T> w = sample_cosine_hemisphere(u1, u2);
  if (!(wo.z < T(0))) w.z = -w.z;
  return w;
}

// Density of lambert_reflection_sample / lambert_transmission_sample.
template <class T>
inline T lambert_reflection_pdf(const Vec3<T>& wi, const Vec3<T>& wo) {
  return cosine_hemisphere_pdf(wi, !(wo.z < T(0)));
}
template <class T>
inline T lambert_transmission_pdf(const Vec3<T>& wi, const Vec3<T>& wo) {
  return cosine_hemisphere_pdf(wi, wo.z < T(0));
}

}  // namespace clothbake::model

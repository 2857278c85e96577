// SpongeCake single scattering (Wang, Jin, Hasan and Yan 2022, "SpongeCake: A Layered Microflake
// Surface Appearance Model") for one slab of fibre-like SGGX microflakes: the specular reflection
// f^{r,s} and transmission f^{t,s} of the cloth BSDF (paper Eq. 1 and 4), their importance
// sampling, and the unscattered transmittance.
//
// Conventions (docs/model.md): i points to the light, o to the viewer, both unit and away from the
// surface, in the local frame (z = macro normal). Values are per steradian, for unit albedo (the
// caller multiplies by the RGB albedo alpha), without any cosine factor. With the optical thickness
// T >= 0 (T = +inf: a semi-infinite slab) and
//
//   Lambda(w) = sigma(w) / |w_z|,   h = normalize(i + o)   (for reflection AND transmission:
//             a specular microflake mirrors i into o, so its normal is i + o; D(h) = D(-h)),
//
//   f_r = D(h) (1 - e^{-T (Lambda_i + Lambda_o)}) / (4 |i_z| |o_z| (Lambda_i + Lambda_o)),
//   f_t = D(h) (e^{-T Lambda_o} - e^{-T Lambda_i}) / (4 |i_z| |o_z| (Lambda_i - Lambda_o)),
//   f_t -> D(h) T e^{-T Lambda} / (4 |i_z| |o_z|)                    as Lambda_i -> Lambda_o,
//   unscattered transmittance e^{-T Lambda(w)}.
//
// Both follow from integrating the phase function D(h) / (4 sigma(i)) over the depth of the slab
// (single scattering, no interfaces). Reflection is i_z o_z > 0, transmission i_z o_z < 0.
//
// Evaluation without cancellation: |i_z| |o_z| (Lambda_i +- Lambda_o) = sigma_i |o_z| +- sigma_o
// |i_z| is formed without dividing by a cosine, 1 - e^{-x} is -expm1(-x), and with
// x = T |Lambda_i - Lambda_o| >= 0,
//
//   f_t = D(h) T e^{-T min(Lambda_i, Lambda_o)} g(x) / (4 |i_z| |o_z|),   g(x) = (1 - e^{-x}) / x,
//
// where g(0) = 1 and g is evaluated as -expm1(-x) / x, accurate for every x > 0; for x > 1 the
// equivalent form with the difference in the denominator is used, which stays finite when a cosine
// underflows. So f_t is continuous through Lambda_i = Lambda_o, T -> 0 gives 0, T -> inf gives the
// semi-infinite form f_r = D / (4 (sigma_i |o_z| + sigma_o |i_z|)) and f_t = 0.
//
// Sampling: draw m from the visible normals of o and reflect, i = 2 (o.m) m - o. The density of i
// is the phase function, pdf(i) = D(h) / (4 sigma(o)) over the whole sphere; i lands above or below
// the surface, so one routine samples both lobes, with weights f cos / pdf bounded by 1 per unit
// albedo: f_r |i_z| / pdf = (1 - e^{-T (L_i + L_o)}) L_o / (L_i + L_o) <= 1.
//
// Header-only, C++17, standard library only, float or double. Every function returns a finite
// value >= 0 for any finite unit directions and T in [0, inf] (safe on untrusted values; NaN T is
// treated as 0). Directions exactly in the surface plane (z = 0) give 0 lobes.
#pragma once

#include <cmath>
#include <limits>

#include "model/sggx.hpp"
#include "model/vec.hpp"

namespace clothbake::model {

namespace spongecake_detail {
// (1 - e^{-x}) / x for x >= 0, with g(0) = 1; accurate for every x (expm1 keeps the digits).
template <class T>
inline T one_minus_exp_over_x(T x) {
  return x > T(0) ? -std::expm1(-x) / x : T(1);
}
template <class T>
inline bool valid_thickness(T thickness) {
  return thickness > T(0);  // false for 0 and NaN
}
}  // namespace spongecake_detail

// Lambda(w) = sigma(w) / |w_z| (+inf in the surface plane).
template <class T>
inline T spongecake_lambda(const FibreSggx<T>& d, const Vec3<T>& w) {
  const T z = std::abs(w.z);
  const T area = d.projected_area(w);
  return z > T(0) ? area / z : std::numeric_limits<T>::infinity();
}

#ifndef CLOTHBAKE_SINGLE_FILE  // the reports', not shading's (the single file leaves it out)
// Unscattered transmittance e^{-T Lambda(w)} of the slab along w, in [0, 1] (1 for T = 0).
template <class T>
inline T spongecake_unscattered_transmittance(const FibreSggx<T>& d, T thickness,
                                              const Vec3<T>& w) {
  if (!spongecake_detail::valid_thickness(thickness)) return T(1);
  return std::exp(-thickness * spongecake_lambda(d, w));
}
#endif

// Specular reflection f^{r,s} per unit albedo; 0 unless i and o are strictly on the same side.
template <class T>
inline T spongecake_reflection(const FibreSggx<T>& d, T thickness, const Vec3<T>& wi,
                               const Vec3<T>& wo) {
  if (!spongecake_detail::valid_thickness(thickness)) return T(0);
  if (!((wi.z > T(0) && wo.z > T(0)) || (wi.z < T(0) && wo.z < T(0)))) return T(0);
  const T iz = std::abs(wi.z), oz = std::abs(wo.z);
  const T si = d.projected_area(wi), so = d.projected_area(wo);
  const T denom = si * oz + so * iz;              // |i_z| |o_z| (Lambda_i + Lambda_o) > 0
  const T tau = thickness * (denom / (iz * oz));  // +inf when a cosine underflows: fine
  const T attenuation = -std::expm1(-tau);
  return d.D(wi + wo) * attenuation / (T(4) * denom);
}

// Specular transmission f^{t,s} per unit albedo; 0 unless i and o are strictly on opposite sides.
template <class T>
inline T spongecake_transmission(const FibreSggx<T>& d, T thickness, const Vec3<T>& wi,
                                 const Vec3<T>& wo) {
  if (!spongecake_detail::valid_thickness(thickness)) return T(0);
  if (!(thickness < std::numeric_limits<T>::infinity())) return T(0);
  if (!((wi.z > T(0) && wo.z < T(0)) || (wi.z < T(0) && wo.z > T(0)))) return T(0);
  const T iz = std::abs(wi.z), oz = std::abs(wo.z);
  const T si = d.projected_area(wi), so = d.projected_area(wo);
  const T lambda_min = std::min(si / iz, so / oz);  // finite: at least one cosine is not tiny
  const T survive = std::exp(-thickness * lambda_min);
  if (!(survive > T(0))) return T(0);
  const T diff = std::abs(si * oz - so * iz);  // |i_z| |o_z| |Lambda_i - Lambda_o|
  const T cosines = iz * oz;
  const T x = thickness * (diff / cosines);  // T |Lambda_i - Lambda_o|, maybe +inf
  const T dh = d.D(wi + wo);
  if (x > T(1)) return dh * survive * (-std::expm1(-x)) / (T(4) * diff);
  return dh * thickness * survive * spongecake_detail::one_minus_exp_over_x(x) / (T(4) * cosines);
}

// Solid-angle density of spongecake_sample over the whole sphere: the SGGX specular phase function
// D(h) / (4 sigma(o)), h = i + o. Integrates to 1 over the sphere for every o.
template <class T>
inline T spongecake_sample_pdf(const FibreSggx<T>& d, const Vec3<T>& wi, const Vec3<T>& wo) {
  const T area = d.projected_area(wo);
  if (!(area > T(0))) return T(0);
  return d.D(wi + wo) / (T(4) * area);
}

// Draws i for outgoing o (unit) by reflecting o about a visible normal of o; u1, u2 in [0, 1].
// Returns a unit vector on either side of the surface (see spongecake_sample_pdf).
template <class T>
inline Vec3<T> spongecake_sample(const FibreSggx<T>& d, const Vec3<T>& wo, T u1, T u2) {
  const Vec3<T> m = d.sample_vndf(wo, u1, u2);
  return normalize(m * (T(2) * dot(wo, m)) - wo);
}

}  // namespace clothbake::model

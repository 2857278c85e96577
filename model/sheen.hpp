// The sheen layer of the cloth BSDF (paper Sec. 3.3, Eq. 4): the volumetric sheen of Zeltner,
// Burley and Chiang 2022, represented by one linearly transformed cosine (LTC, Heitz et al. 2016)
// per (cos theta_o, roughness), tabulated by `clothbake fit-sheen` in two conventions
// (docs/sheen.md): model/sheen_table.hpp, the published one of Zeltner et al. (paths cut after 16
// scattering events and classified by their last direction, cos theta and roughness simulated at >=
// 0.01; what Cycles and OpenPBR renderers use), the default; model/sheen_table_converged.hpp, every
// path followed until it leaves the layer, on request (SheenConvention::Converged).
//
// In the frame of wo (x axis = azimuth of wo, z = macro normal) the cosine-weighted lobe is
//
//   f_sheen(wi, wo) cos theta_i = colour * R * D(wi),
//   D(w) = D_o(M^-1 w / |M^-1 w|) |det M^-1| / |M^-1 w|^3 = a^2 max(w.z, 0) / (pi |M^-1 w|^4),
//   M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]],   D_o(w) = max(w.z, 0) / pi,
//
// where R is the directional albedo of the simulated layer. M^-1 keeps the z component, so D lives
// on the upper hemisphere and integrates to exactly 1 there: sheen_sample draws wi from D with
// weight R, and the energy left for the layers below is T_sheen = 1 - colour * R (Eq. 4).
// The lobe is not exactly reciprocal (the cosine of wi is baked in, as in Zeltner et al.).
//
// Header-only, C++17, standard library only, float or double. Every function is total: inputs are
// clamped (cos theta and roughness to [0, 1], NaN to 0), so they are safe on untrusted values.
#pragma once

#include <algorithm>
#include <cmath>

#include "model/directions.hpp"  // kPi
#include "model/sheen_table.hpp"
#include "model/sheen_table_converged.hpp"
#include "model/vec.hpp"

namespace clothbake::model {

// Which fitted sheen table the lobe uses. Published (the default): the simulation rules of
// Zeltner et al.'s published table, so that renders agree with renderers that ship it; Converged:
// the layer's exact albedo, which at low roughness and grazing incidence is much larger (up to
// R = 0.748 against 0.058, docs/sheen.md). Any other value behaves as Published.
enum class SheenConvention : int { Published = 0, Converged = 1 };

#ifndef CLOTHBAKE_SINGLE_FILE  // the tools', not shading's (the single file leaves it out)
inline const char* sheen_convention_name(SheenConvention convention) {
  return convention == SheenConvention::Converged ? "converged" : "published";
}
#endif

// LTC coefficients of one (cos theta_o, roughness): M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]] in
// the frame of wo, and the directional albedo R of the sheen layer (R in [0, 1], a > 0).
template <class T>
struct SheenLtc {
  T a, b, albedo;
};

namespace sheen_detail {

// Clamps x to [0, 1]; NaN becomes 0 (comparisons with NaN are false).
template <class T>
inline T unit_clamp(T x) {
  return x > T(0) ? (x < T(1) ? x : T(1)) : T(0);
}

// Frame of wo: x axis along the azimuth of wo (wo = (sin theta_o, 0, cos theta_o) in it). At the
// pole the azimuth is undefined; the table's b is 0 there (the lobe is rotationally symmetric), so
// any choice is continuous.
template <class T>
inline void wo_azimuth(const Vec3<T>& wo, T& cos_phi, T& sin_phi) {
  T planar = std::sqrt(wo.x * wo.x + wo.y * wo.y);
  if (planar > T(1e-12)) {
    cos_phi = wo.x / planar;
    sin_phi = wo.y / planar;
  } else {
    cos_phi = T(1);
    sin_phi = T(0);
  }
}

// |M^-1 w|^2 for w in the frame of wo.
template <class T>
inline T inverse_transformed_length2(const SheenLtc<T>& ltc, T x, T y, T z) {
  T tx = ltc.a * x + ltc.b * z;
  T ty = ltc.a * y;
  return tx * tx + ty * ty + z * z;
}

}  // namespace sheen_detail

namespace sheen_detail {

// Bilinear lookup of one table kTable[roughness][cos][{a, b, R}] with nodes at i / (C - 1).
template <class T, int R, int C>
inline SheenLtc<T> table_lookup(const float (&table)[R][C][3], T cos_theta_o, T roughness) {
  static_assert(C >= 2 && R >= 2, "a sheen table needs 2 x 2 nodes");
  const T u = unit_clamp(cos_theta_o) * T(C - 1);
  const T v = unit_clamp(roughness) * T(R - 1);
  const int i0 = std::min(int(u), C - 2);
  const int j0 = std::min(int(v), R - 2);
  const T tu = u - T(i0), tv = v - T(j0);
  T out[3];
  for (int k = 0; k < 3; ++k) {
    const T c00 = T(table[j0][i0][k]), c10 = T(table[j0][i0 + 1][k]);
    const T c01 = T(table[j0 + 1][i0][k]), c11 = T(table[j0 + 1][i0 + 1][k]);
    out[k] = (T(1) - tv) * ((T(1) - tu) * c00 + tu * c10) + tv * ((T(1) - tu) * c01 + tu * c11);
  }
  return {out[0], out[1], out[2]};
}

}  // namespace sheen_detail

// Bilinear lookup of the fitted table of the given convention at (cos theta_o, sheen roughness).
// Both inputs are clamped to [0, 1] (NaN to 0). Returns a > 0, finite b, R in [0, 1].
template <class T>
inline SheenLtc<T> sheen_ltc(T cos_theta_o, T roughness,
                             SheenConvention convention = SheenConvention::Published) {
  if (convention == SheenConvention::Converged)
    return sheen_detail::table_lookup(sheen_table_converged::kTable, cos_theta_o, roughness);
  return sheen_detail::table_lookup(sheen_table::kTable, cos_theta_o, roughness);
}

// Directional albedo R of the sheen layer for light arriving from (or leaving towards) a direction
// with cosine cos_theta_o to the normal, in [0, 1]. Eq. 4 uses T_sheen = 1 - colour * R.
template <class T>
inline T sheen_albedo(T cos_theta_o, T roughness,
                      SheenConvention convention = SheenConvention::Published) {
  return sheen_ltc(cos_theta_o, roughness, convention).albedo;
}

// The normalised LTC density D(wi) of a given lobe for wo (unit vectors, local frame), per
// steradian: 0 unless wi.z > 0 and wo.z > 0. Exposed for tests and the fitting tool.
template <class T>
inline T sheen_ltc_density(const SheenLtc<T>& ltc, const Vec3<T>& wi, const Vec3<T>& wo) {
  if (!(wi.z > T(0)) || !(wo.z > T(0))) return T(0);
  T c, s;
  sheen_detail::wo_azimuth(wo, c, s);
  const T x = wi.x * c + wi.y * s, y = -wi.x * s + wi.y * c;
  const T len2 = sheen_detail::inverse_transformed_length2(ltc, x, y, wi.z);
  return ltc.a * ltc.a * wi.z / (kPi<T> * len2 * len2);
}

// The sheen BSDF value for unit colour (no cosine factor): R D(wi) / cos theta_i, for unit wi, wo
// in the local frame. 0 unless wi.z > 0 and wo.z > 0. Finite at grazing wi: the cosine cancels
// analytically (f = R a^2 / (pi |M^-1 wi|^4)).
template <class T>
inline T sheen_eval(const Vec3<T>& wi, const Vec3<T>& wo, T roughness,
                    SheenConvention convention = SheenConvention::Published) {
  if (!(wi.z > T(0)) || !(wo.z > T(0))) return T(0);
  const SheenLtc<T> ltc = sheen_ltc(wo.z, roughness, convention);
  T c, s;
  sheen_detail::wo_azimuth(wo, c, s);
  const T x = wi.x * c + wi.y * s, y = -wi.x * s + wi.y * c;
  const T len2 = sheen_detail::inverse_transformed_length2(ltc, x, y, wi.z);
  return ltc.albedo * ltc.a * ltc.a / (kPi<T> * len2 * len2);
}

// Solid-angle pdf of sheen_sample: the LTC density D(wi). 0 unless wi.z > 0 and wo.z > 0.
template <class T>
inline T sheen_pdf(const Vec3<T>& wi, const Vec3<T>& wo, T roughness,
                   SheenConvention convention = SheenConvention::Published) {
  if (!(wo.z > T(0))) return T(0);
  return sheen_ltc_density(sheen_ltc(wo.z, roughness, convention), wi, wo);
}

// Draws wi from the LTC density of a given lobe for wo with uniform numbers u1, u2 in [0, 1): a
// cosine-distributed direction mapped by M. Returns a unit vector with z >= 0, or the zero vector
// if wo.z <= 0. Exposed for tests and the fitting tool.
template <class T>
inline Vec3<T> sheen_ltc_sample(const SheenLtc<T>& ltc, const Vec3<T>& wo, T u1, T u2) {
  if (!(wo.z > T(0))) return {T(0), T(0), T(0)};
  // Cosine-weighted hemisphere (Malley's method on the unit disk).
  const T r = std::sqrt(sheen_detail::unit_clamp(u1));
  const T phi = T(2) * kPi<T> * sheen_detail::unit_clamp(u2);
  const T ox = r * std::cos(phi), oy = r * std::sin(phi);
  const T oz = std::sqrt(std::max(T(0), T(1) - r * r));
  // M = [[1/a, 0, -b/a], [0, 1/a, 0], [0, 0, 1]].
  const Vec3<T> local = normalize(Vec3<T>{(ox - ltc.b * oz) / ltc.a, oy / ltc.a, oz});
  T c, s;
  sheen_detail::wo_azimuth(wo, c, s);
  return {local.x * c - local.y * s, local.x * s + local.y * c, local.z};
}

// Draws wi from the sheen lobe of wo with uniform numbers u1, u2 in [0, 1). The estimator weight
// f cos / pdf is exactly sheen_albedo(wo.z, roughness, convention). Returns a unit vector with z >=
// 0, or the zero vector if wo.z <= 0 (no sheen from below).
template <class T>
inline Vec3<T> sheen_sample(const Vec3<T>& wo, T roughness, T u1, T u2,
                            SheenConvention convention = SheenConvention::Published) {
  if (!(wo.z > T(0))) return {T(0), T(0), T(0)};
  return sheen_ltc_sample(sheen_ltc(wo.z, roughness, convention), wo, u1, u2);
}

}  // namespace clothbake::model

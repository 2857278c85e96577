// Fibre-like SGGX microflake distribution (Heitz, Dupuy, Crassin and Dachsbacher 2015, "The SGGX
// microflake distribution"), as used by the cloth BSDF for the specular lobes (paper Sec. 3.1).
//
// For a fibre with unit tangent t and roughness sigma the SGGX matrix is
//
//   S = sigma^2 t t^T + (I - t t^T),   |S| = sigma^2,   S^-1 = sigma^-2 t t^T + (I - t t^T),
//   D(m)     = 1 / (pi sqrt|S| (m^T S^-1 m)^2)        (normals concentrate perpendicular to t),
//   sigma(w) = sqrt(w^T S w)                            (projected area of the flakes seen from w),
//   D_w(m)   = <w, m>^+ D(m) / sigma(w)                 (visible normals; integrates to 1).
//
// Normalisation: the integral of D(m) <w, m>^+ over the sphere is sigma(w) (so the integral of D
// over the sphere is 4 for S = I); D(m) = D(-m).
//
// Numerics. Forming S^-1 for sigma = 1e-3 gives entries of 1e6 and cancellation; instead everything
// is written in the fibre frame with bounded coefficients. With c = t.m and unit m,
//
//   sigma^2 m^T S^-1 m = sigma^2 + (1 - sigma^2) c^2         (a sum of non-negative terms),
//   D(m)               = sigma^3 / (pi (sigma^2 + (1 - sigma^2) c^2)^2),
//   sigma(w)^2         = sigma^2 c^2 + |t x w|^2              (no 1 - c^2 cancellation),
//
// so the per-texel constants are t, sigma^2, 1 - sigma^2 and sigma^3 / pi (the factored scaled
// inverse sigma^2 S^-1 and sqrt|S| = sigma). Both D and sigma(w) are homogeneous (of degree 0 and 1
// in m and w), so an unnormalised half vector i + o can be passed directly.
//
// Visible-normal sampling uses the ellipsoid picture of SGGX: D is the normal distribution of the
// ellipsoid x^T S x = 1, i.e. of A(unit sphere) with A = S^-1/2. Parallel rays along w, mapped by
// A^-1 = S^1/2 = I + (sigma - 1) t t^T, stay parallel (direction S^1/2 w) and uniform, so the hit
// point on the unit sphere is cosine-distributed about w' = normalize(S^1/2 w), and the ellipsoid
// normal there is normalize(S^1/2 u). This needs no inverse and no square root of a small
// determinant (our own derivation; Heitz et al. give an equivalent construction in an arbitrary
// basis).
//
// Header-only, C++17, standard library only, float or double. All functions are total: the
// factory clamps roughness to [kMinFibreRoughness, 1] and replaces a zero or non-finite tangent
// by +z, so values are finite and >= 0 for any finite input (safe on untrusted values).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/directions.hpp"  // kPi, concentric_square_to_disk
#include "model/vec.hpp"

namespace clothbake::model {

// Smallest fibre roughness the model accepts (sigma^3 must stay a normal float: 1e-12 > 1.2e-38).
template <class T>
inline constexpr T kMinFibreRoughness = T(1e-4);

#ifndef CLOTHBAKE_SINGLE_FILE  // reference and tests only
// A symmetric 3x3 matrix (reference and tests only; the distribution never forms S^-1).
template <class T>
struct SymMat3 {
  T xx, yy, zz, xy, xz, yz;
};
#endif

// One texel's fibre-like SGGX distribution with its constants precomputed (cheap to evaluate).
template <class T>
struct FibreSggx {
  Vec3<T> t{T(0), T(0), T(1)};  // unit fibre tangent, local frame
  T sigma = T(1);               // roughness, in [kMinFibreRoughness, 1]; also sqrt|S|
  T sigma2 = T(1);              // sigma^2
  T one_minus_sigma2 = T(0);    // 1 - sigma^2: coefficient of (t.m)^2 in sigma^2 m^T S^-1 m
  T d_norm = T(1) / kPi<T>;     // sigma^3 / pi

  // Builds the distribution of tangent `tangent` (any length; normalised here) and roughness
  // `roughness` (clamped to [kMinFibreRoughness, 1], NaN -> 1). A zero or non-finite tangent
  // becomes +z. Never fails.
  static FibreSggx make(const Vec3<T>& tangent, T roughness) {
    FibreSggx d;
    T len = length(tangent);
    if (std::isfinite(len) && len > T(0))
      d.t = tangent / len;
    else
      d.t = {T(0), T(0), T(1)};
    T s = roughness;
    if (!(s >= kMinFibreRoughness<T>)) s = std::isnan(roughness) ? T(1) : kMinFibreRoughness<T>;
    if (s > T(1)) s = T(1);
    d.sigma = s;
    d.sigma2 = s * s;
    d.one_minus_sigma2 = (T(1) - s) * (T(1) + s);
    d.d_norm = s * s * s / kPi<T>;
    return d;
  }

#ifndef CLOTHBAKE_SINGLE_FILE  // reference and tests only
  // sqrt(det S) = sigma.
  T sqrt_det() const {
    return sigma;
  }

  // S itself, for reference and tests.
  SymMat3<T> matrix() const {
    const T k = sigma2 - T(1);  // S = I + (sigma^2 - 1) t t^T
    return {T(1) + k * t.x * t.x, T(1) + k * t.y * t.y, T(1) + k * t.z * t.z,
            k * t.x * t.y,        k * t.x * t.z,        k * t.y * t.z};
  }

  // S^-1 = I + (sigma^-2 - 1) t t^T, for reference and tests (ill-conditioned for small sigma: the
  // distribution itself never uses it).
  SymMat3<T> inverse_matrix() const {
    const T k = T(1) / sigma2 - T(1);
    return {T(1) + k * t.x * t.x, T(1) + k * t.y * t.y, T(1) + k * t.z * t.z,
            k * t.x * t.y,        k * t.x * t.z,        k * t.y * t.z};
  }
#endif

  // D(m / |m|) for any non-zero m (per steradian, >= 0, at most 1 / (pi sigma)). Returns 0 for the
  // zero vector (the half vector of exactly opposite directions).
  T D(const Vec3<T>& m) const {
    const T mm = dot(m, m);
    if (!(mm > std::numeric_limits<T>::min())) return T(0);
    const T c = dot(t, m);
    const T q = sigma2 * mm + one_minus_sigma2 * (c * c);  // sigma^2 m^T S^-1 m, times |m|^2
    const T ratio = mm / q;
    return d_norm * ratio * ratio;
  }

  // Projected area sigma(w) = sqrt(w^T S w), in [sigma |w|, |w|]; homogeneous of degree 1.
  T projected_area(const Vec3<T>& w) const {
    const T c = dot(t, w);
    const Vec3<T> x = cross(t, w);
    return std::sqrt(sigma2 * (c * c) + dot(x, x));
  }

#ifndef CLOTHBAKE_SINGLE_FILE  // the batched loops' and the tests', not shading's
  // D(m) for a unit vector m: the form the batched loops use (model/sggx_batch.hpp).
  T D_unit(const Vec3<T>& m) const {
    const T c = dot(t, m);
    const T q = sigma2 + one_minus_sigma2 * (c * c);
    return d_norm / (q * q);
  }

  // Visible-normal density D_w(m) = <w, m>^+ D(m) / sigma(w) for unit w and m, per steradian of m.
  T vndf_pdf(const Vec3<T>& w, const Vec3<T>& m) const {
    const T wm = dot(w, m);
    if (!(wm > T(0))) return T(0);
    const T area = projected_area(w);
    if (!(area > T(0))) return T(0);
    return wm * D(m) / area;
  }
#endif

  // S^1/2 v = v + (sigma - 1) (t.v) t.
  Vec3<T> apply_sqrt_s(const Vec3<T>& v) const {
    return v + t * ((sigma - T(1)) * dot(t, v));
  }

  // Draws a unit normal m from D_w (unit w) with uniform numbers u1, u2 in [0, 1]; w.m >= 0.
  Vec3<T> sample_vndf(const Vec3<T>& w, T u1, T u2) const {
    const Vec3<T> ws = normalize(apply_sqrt_s(w));
    Vec3<T> e1, e2;
    orthonormal_basis(ws, e1, e2);
    T x, y;
    concentric_square_to_disk(T(2) * u1 - T(1), T(2) * u2 - T(1), x, y);
    const T z = std::sqrt(std::max(T(0), T(1) - x * x - y * y));
    const Vec3<T> u = e1 * x + e2 * y + ws * z;  // cosine-distributed about ws on the unit sphere
    return normalize(apply_sqrt_s(u));
  }
};

}  // namespace clothbake::model

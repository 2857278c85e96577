// Batched evaluation of the fibre-like SGGX distribution D (model/sggx.hpp) in structure-of-arrays
// form, for filling Integral-Radiance tables (paper Sec. 4.3, Eq. 11): D over many texels for one
// half vector, and D over many half vectors for one texel.
//
// The loops are branch-free straight-line arithmetic over restrict-qualified arrays, written so
// that GCC auto-vectorises them at -O3, the project's Release level (check with -fopt-info-vec;
// GCC 12 at plain -O2 does not: its "very cheap" cost model refuses loops of unknown trip count,
// so a renderer including this header at -O2 needs -ftree-vectorize -fvect-cost-model=dynamic or
// -O3 for these loops). Per element
//   c = t.h,  q = sigma^2 + (1 - sigma^2) c^2,  D = (sigma^3 / pi) / q^2
// for unit h. Results equal FibreSggx::D_unit element by element (same operations, same order,
// apart from the fused multiply-adds the compiler may contract on targets that have them).
//
// Header-only, C++17, standard library only, float or double. Callers pass unit half vectors;
// pointers must not alias the output. Safe for any finite input (no branches, no division by a
// value that can reach zero: q >= sigma^2 >= 1e-8).
#pragma once

#include <cstddef>
#include <vector>

#include "model/sggx.hpp"
#include "model/vec.hpp"

#if defined(__GNUC__) || defined(__clang__)
#define CLOTHBAKE_RESTRICT __restrict__
#else
#define CLOTHBAKE_RESTRICT
#endif

namespace clothbake::model {

// Per-texel SGGX constants, one array per field (structure of arrays).
template <class T>
struct FibreSggxBatch {
  std::vector<T> tx, ty, tz;        // unit tangent
  std::vector<T> sigma2;            // sigma^2
  std::vector<T> one_minus_sigma2;  // 1 - sigma^2
  std::vector<T> d_norm;            // sigma^3 / pi

  std::size_t size() const { return tx.size(); }
  void resize(std::size_t n) {
    tx.resize(n);
    ty.resize(n);
    tz.resize(n);
    sigma2.resize(n);
    one_minus_sigma2.resize(n);
    d_norm.resize(n);
  }
  void set(std::size_t i, const FibreSggx<T>& d) {
    tx[i] = d.t.x;
    ty[i] = d.t.y;
    tz[i] = d.t.z;
    sigma2[i] = d.sigma2;
    one_minus_sigma2[i] = d.one_minus_sigma2;
    d_norm[i] = d.d_norm;
  }
  void push_back(const FibreSggx<T>& d) {
    resize(size() + 1);
    set(size() - 1, d);
  }
};

// out[i] = D_i(h) for texels i = 0 .. n-1 and one unit half vector h (raw arrays).
template <class T>
inline void sggx_d_over_texels(std::size_t n, const T* CLOTHBAKE_RESTRICT tx,
                               const T* CLOTHBAKE_RESTRICT ty, const T* CLOTHBAKE_RESTRICT tz,
                               const T* CLOTHBAKE_RESTRICT sigma2,
                               const T* CLOTHBAKE_RESTRICT one_minus_sigma2,
                               const T* CLOTHBAKE_RESTRICT d_norm, const Vec3<T>& h,
                               T* CLOTHBAKE_RESTRICT out) {
  const T hx = h.x, hy = h.y, hz = h.z;
  for (std::size_t i = 0; i < n; ++i) {
    const T c = tx[i] * hx + ty[i] * hy + tz[i] * hz;
    const T q = sigma2[i] + one_minus_sigma2[i] * (c * c);
    out[i] = d_norm[i] / (q * q);
  }
}

// out[i] = D_i(h) for every texel of `batch` (out has batch.size() entries).
template <class T>
inline void sggx_d_over_texels(const FibreSggxBatch<T>& batch, const Vec3<T>& h, T* out) {
  sggx_d_over_texels(batch.size(), batch.tx.data(), batch.ty.data(), batch.tz.data(),
                     batch.sigma2.data(), batch.one_minus_sigma2.data(), batch.d_norm.data(), h,
                     out);
}

// acc[i] += weight * D_i(h): accumulates a quadrature rule over a half-vector bin (bin averages,
// DESIGN.md "Bins store bin averages") without a temporary array.
template <class T>
inline void sggx_d_over_texels_accumulate(const FibreSggxBatch<T>& batch, const Vec3<T>& h,
                                          T weight, T* CLOTHBAKE_RESTRICT acc) {
  const std::size_t n = batch.size();
  const T* CLOTHBAKE_RESTRICT tx = batch.tx.data();
  const T* CLOTHBAKE_RESTRICT ty = batch.ty.data();
  const T* CLOTHBAKE_RESTRICT tz = batch.tz.data();
  const T* CLOTHBAKE_RESTRICT s2 = batch.sigma2.data();
  const T* CLOTHBAKE_RESTRICT k = batch.one_minus_sigma2.data();
  const T* CLOTHBAKE_RESTRICT norm = batch.d_norm.data();
  const T hx = h.x, hy = h.y, hz = h.z;
  for (std::size_t i = 0; i < n; ++i) {
    const T c = tx[i] * hx + ty[i] * hy + tz[i] * hz;
    const T q = s2[i] + k[i] * (c * c);
    acc[i] += weight * (norm[i] / (q * q));
  }
}

// out[j] = D(h_j) of one texel for unit half vectors h_j = (hx[j], hy[j], hz[j]), j = 0 .. n-1.
template <class T>
inline void sggx_d_over_directions(const FibreSggx<T>& texel, std::size_t n,
                                   const T* CLOTHBAKE_RESTRICT hx, const T* CLOTHBAKE_RESTRICT hy,
                                   const T* CLOTHBAKE_RESTRICT hz, T* CLOTHBAKE_RESTRICT out) {
  const T tx = texel.t.x, ty = texel.t.y, tz = texel.t.z;
  const T s2 = texel.sigma2, k = texel.one_minus_sigma2, norm = texel.d_norm;
  for (std::size_t j = 0; j < n; ++j) {
    const T c = tx * hx[j] + ty * hy[j] + tz * hz[j];
    const T q = s2 + k * (c * c);
    out[j] = norm / (q * q);
  }
}

}  // namespace clothbake::model

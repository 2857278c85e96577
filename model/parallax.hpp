// Parallax offset of paper Eq. 2 and the tile-wrap helpers of texel space.
//
//   u_new = u + (r / o_z) (o_x, o_y)
//
// u in texel space ([0, 1)^2 over one tile), o the unit view direction in the local frame (z =
// macro normal, +x = u, +y = v), r the ray depth in tile-side units (the unit of the height map,
// DESIGN.md), as baked by the parallax stage for o_z > 0.6 (Sec. 3.2). The result may leave the
// tile; wrap it with wrap_tile. The sign follows Eq. 2 as printed: r is the signed depth the
// parallax stage stores (docs/model.md).
//
// Header-only, C++17, standard library only, float or double; total functions (safe on any input).
#pragma once

#include <cmath>

#include "model/vec.hpp"

namespace clothbake::model {

template <class T>
struct TexelPoint {
  T u{}, v{};
};

// Eq. 2. For o_z <= 0 (no parallax table there) or a non-finite offset, returns (u, v) unchanged.
template <class T>
inline TexelPoint<T> parallax_offset(TexelPoint<T> p, const Vec3<T>& wo, T depth) {
  if (!(wo.z > T(0))) return p;
  const T s = depth / wo.z;
  const T du = s * wo.x, dv = s * wo.y;
  if (!std::isfinite(du) || !std::isfinite(dv)) return p;
  return {p.u + du, p.v + dv};
}

// Wraps a texel-space coordinate into [0, 1) (periodic tile). Non-finite input gives 0. The result
// is strictly below 1 even when u is a tiny negative number (where u - floor(u) rounds to 1).
template <class T>
inline T wrap_tile(T u) {
  if (!std::isfinite(u)) return T(0);
  T w = u - std::floor(u);
  if (!(w < T(1))) w = T(0);  // -1e-20 - floor(-1e-20) == 1 in floating point: that is 0 mod 1
  return w;
}

template <class T>
inline TexelPoint<T> wrap_tile(TexelPoint<T> p) {
  return {wrap_tile(p.u), wrap_tile(p.v)};
}

// Wraps an integer texel index into [0, n) (n > 0), for any i including negative values.
inline int wrap_texel(long long i, int n) {
  long long r = i % n;
  return int(r < 0 ? r + n : r);
}

// Texel index (x, y) of a wrapped point on an n x n tile: texel x covers [x/n, (x+1)/n).
template <class T>
inline void texel_of(TexelPoint<T> p, int n, int& x, int& y) {
  const TexelPoint<T> w = wrap_tile(p);
  x = wrap_texel((long long)std::floor(w.u * T(n)), n);
  y = wrap_texel((long long)std::floor(w.v * T(n)), n);
}

}  // namespace clothbake::model

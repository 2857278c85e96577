// The one directional parameterisation of every clothbake table (parallax view directions,
// visibility light directions, Integral-Radiance half-vector bins): an equal-area map from the unit
// square to a spherical cap z >= min_cos (min_cos = 0: the upper hemisphere; 0.6: the parallax cap
// of paper Sec. 3.2).
//
//   square (u, v) in [0,1]^2 --Shirley-Chiu concentric map--> unit disk (x, y), area-preserving
//   disk --lift--> cap:  z = 1 - r^2 (1 - min_cos),  (dx, dy) = (x, y) * sqrt(1 - z^2) / r
//
// The lift maps disk area pi onto cap solid angle 2 pi (1 - min_cos) with constant Jacobian, so
// equal areas of the square are equal solid angles: every one of the n x n bins covers 2 pi (1 -
// min_cos) / n^2 sr. The map is continuous inside the square (kinks only on the diagonals), so
// bilinear interpolation between bin centres has no seam except at the border. Bin (i, j) covers u
// in [i/n, (i+1)/n), v in [j/n, (j+1)/n); its index is j * n + i.
//
// Header-only, C++17, standard library only; safe for any finite input (directions outside the cap
// are clamped onto its rim; the zero vector maps to the cap's pole).
#pragma once

#include <algorithm>
#include <cmath>

#include "model/vec.hpp"

namespace clothbake::model {

template <class T>
inline constexpr T kPi = T(3.14159265358979323846264338327950288);
template <class T>
inline constexpr T kInvPi = T(0.318309886183790671537767526745028724);

// Square [-1,1]^2 -> unit disk, area-preserving (Shirley and Chiu 1997).
template <class T>
inline void concentric_square_to_disk(T a, T b, T& x, T& y) {
  if (a == T(0) && b == T(0)) {
    x = y = T(0);
    return;
  }
  T r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = (kPi<T> / 4) * (b / a);
  } else {
    r = b;
    phi = kPi<T> / 2 - (kPi<T> / 4) * (a / b);
  }
  x = r * std::cos(phi);
  y = r * std::sin(phi);
}

// Unit disk -> square [-1,1]^2, the inverse of concentric_square_to_disk.
template <class T>
inline void concentric_disk_to_square(T x, T y, T& a, T& b) {
  T r = std::sqrt(x * x + y * y);
  if (r == T(0)) {
    a = b = T(0);
    return;
  }
  T phi = std::atan2(y, x);
  if (phi < -kPi<T> / 4) phi += 2 * kPi<T>;
  const T quarter = kPi<T> / 4;
  if (phi < quarter) {
    a = r;
    b = phi * a / quarter;
  } else if (phi < 3 * quarter) {
    b = r;
    a = -(phi - kPi<T> / 2) * b / quarter;
  } else if (phi < 5 * quarter) {
    a = -r;
    b = (phi - kPi<T>)*a / quarter;
  } else {
    b = -r;
    a = -(phi - 3 * kPi<T> / 2) * b / quarter;
  }
}

// atan(t) / (pi / 4) for t in [-1, 1], without atan: an odd polynomial of degree 17 fitted to
// minimise the maximum error on [0, 1] (Lawson-weighted least squares on Chebyshev nodes; max
// |error| in atan about 6e-9 rad, so the quarter-turn result is off by < 1e-8). What the radiance
// footprint queries' direction lookup (DirectionGrid::to_square_fast, bilinear_fast) uses instead
// of atan2, which cost about half of such a query.
template <class T>
inline T quarter_turns_of_atan(T t) {
  const T s = t * t;
  T p = T(0.002456725370622817);
  p = p * s + T(-0.014401361523145792);
  p = p * s + T(0.039781230424798614);
  p = p * s + T(-0.07234858065250171);
  p = p * s + T(0.10498946485148122);
  p = p * s + T(-0.14161229331228506);
  p = p * s + T(0.19985906791403882);
  p = p * s + T(-0.33332597030294403);
  p = p * s + T(0.9999998863836109);
  return t * p * T(1.27323954473516268615);  // 4 / pi
}

// Four bins and weights of a bilinear lookup; weights are >= 0 and sum to 1.
template <class T>
struct BinBilinear {
  int index[4];
  T weight[4];
};

// An n x n equal-area grid of directions over the cap z >= min_cos.
template <class T>
struct DirectionGrid {
  int n = 32;
  T min_cos = T(0);

  // Direction of square point (u, v) in [0,1]^2 (clamped). Unit length, z >= min_cos.
  Vec3<T> direction(T u, T v) const {
    u = std::clamp(u, T(0), T(1));
    v = std::clamp(v, T(0), T(1));
    T x, y;
    concentric_square_to_disk(2 * u - 1, 2 * v - 1, x, y);
    T r2 = std::min(x * x + y * y, T(1));
    T z = T(1) - r2 * (T(1) - min_cos);
    T r = std::sqrt(r2);
    if (r == T(0)) return {T(0), T(0), T(1)};
    T s = std::sqrt(std::max(T(0), T(1) - z * z)) / r;
    return {x * s, y * s, z};
  }

  // Square point of direction d (need not be normalised). Directions below the cap map onto its
  // rim.
  void to_square(const Vec3<T>& d, T& u, T& v) const {
    T len = length(d);
    if (!(len > T(0))) {
      u = v = T(0.5);
      return;
    }
    T z = std::clamp(d.z / len, min_cos, T(1));
    T r2 = (T(1) - z) / (T(1) - min_cos);
    T r = std::sqrt(std::clamp(r2, T(0), T(1)));
    T planar = std::sqrt(d.x * d.x + d.y * d.y);
    T x = T(0), y = T(0);
    if (planar > T(0)) {
      x = r * d.x / planar;
      y = r * d.y / planar;
    }
    T a, b;
    concentric_disk_to_square(x, y, a, b);
    u = std::clamp((a + 1) / 2, T(0), T(1));
    v = std::clamp((b + 1) / 2, T(0), T(1));
  }

  // to_square without atan2 and with one square root fewer: the same map (the octant's atan of
  // a ratio in [-1, 1] by quarter_turns_of_atan), equal to to_square within 1e-8 in u and v.
  // Directions on an octant boundary (|x| = |y|) are continuous across it, so either side gives
  // the same point.
  void to_square_fast(const Vec3<T>& d, T& u, T& v) const {
    const T len2 = d.x * d.x + d.y * d.y + d.z * d.z;
    if (!(len2 > T(0))) {
      u = v = T(0.5);
      return;
    }
    const T z = std::clamp(d.z / std::sqrt(len2), min_cos, T(1));
    const T r = std::sqrt(std::clamp((T(1) - z) / (T(1) - min_cos), T(0), T(1)));
    const T ax = std::abs(d.x), ay = std::abs(d.y);
    T a = T(0), b = T(0);
    if (ax >= ay) {
      if (ax > T(0)) {  // |phi| <= pi/4 (x > 0) or |phi - pi| <= pi/4 (x < 0)
        const T signed_r = d.x > T(0) ? r : -r;
        a = signed_r;
        b = signed_r * quarter_turns_of_atan(d.y / d.x);
      }
    } else {  // |phi - pi/2| < pi/4 (y > 0) or |phi + pi/2| < pi/4 (y < 0)
      const T signed_r = d.y > T(0) ? r : -r;
      b = signed_r;
      a = signed_r * quarter_turns_of_atan(d.x / d.y);
    }
    u = std::clamp((a + 1) / 2, T(0), T(1));
    v = std::clamp((b + 1) / 2, T(0), T(1));
  }

  int bin_index(int i, int j) const { return j * n + i; }
  Vec3<T> bin_center(int i, int j) const {
    return direction((T(i) + T(0.5)) / T(n), (T(j) + T(0.5)) / T(n));
  }

#ifndef CLOTHBAKE_SINGLE_FILE  // the bake's and the tools', not shading's
  int bin_count() const {
    return n * n;
  }
  // Solid angle of every bin, in steradians.
  T bin_solid_angle() const {
    return 2 * kPi<T> * (T(1) - min_cos) / T(n * n);
  }
  // The bin that contains direction d (directions below the cap: the nearest rim bin).
  int bin_of(const Vec3<T>& d) const {
    T u, v;
    to_square(d, u, v);
    int i = std::min(int(u * T(n)), n - 1);
    int j = std::min(int(v * T(n)), n - 1);
    return bin_index(i, j);
  }
#endif

  // Bilinear weights over the 4 bin centres nearest to d in the square; clamped at the border
  // (a direction outside the outermost bin centres takes the border bins' values).
  BinBilinear<T> bilinear(const Vec3<T>& d) const {
    T u, v;
    to_square(d, u, v);
    return bilinear_at(u, v);
  }
  // The same through to_square_fast (no atan2): weights equal bilinear's within n * 1e-8. What
  // the radiance footprint queries use (formats/reader/radiance_query.cpp).
  BinBilinear<T> bilinear_fast(const Vec3<T>& d) const {
    T u, v;
    to_square_fast(d, u, v);
    return bilinear_at(u, v);
  }
  // Bilinear weights at square point (u, v) in [0, 1]^2.
  BinBilinear<T> bilinear_at(T u, T v) const {
    T fx = std::clamp(u * T(n) - T(0.5), T(0), T(n - 1));
    T fy = std::clamp(v * T(n) - T(0.5), T(0), T(n - 1));
    int i0 = std::min(int(fx), n - 1), j0 = std::min(int(fy), n - 1);
    int i1 = std::min(i0 + 1, n - 1), j1 = std::min(j0 + 1, n - 1);
    T tx = fx - T(i0), ty = fy - T(j0);
    BinBilinear<T> w;
    w.index[0] = bin_index(i0, j0);
    w.weight[0] = (1 - tx) * (1 - ty);
    w.index[1] = bin_index(i1, j0);
    w.weight[1] = tx * (1 - ty);
    w.index[2] = bin_index(i0, j1);
    w.weight[2] = (1 - tx) * ty;
    w.index[3] = bin_index(i1, j1);
    w.weight[3] = tx * ty;
    return w;
  }
};

// SGGX is centrally symmetric, D(h) = D(-h): tables store the upper hemisphere only.
template <class T>
inline Vec3<T> fold_to_upper_hemisphere(const Vec3<T>& h) {
  return h.z < T(0) ? -h : h;
}

}  // namespace clothbake::model

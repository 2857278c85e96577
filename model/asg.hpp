// Anisotropic spherical Gaussian (ASG) visibility lobes (Xu et al. 2013, "Anisotropic Spherical
// Gaussians"), as used for the per-texel visibility V(x, i) of paper Eq. 3 (Sec. 3.1, 4.2).
//
//   G(v) = c * [v.z > 0] * exp(-lambda (v.x)^2 - mu (v.y)^2)      (v.x = dot(v, x), etc.)
//
// with an orthonormal frame (x, y, z): z is the lobe axis, x and y its tangent axes; lambda, mu >=
// 0 are the bandwidths along x and y and c >= 0 is the amplitude. This differs from Xu et al.'s ASG
// in one respect, on purpose: their smooth term max(v.z, 0) is replaced by the hemisphere indicator
// [v.z > 0]. With the smooth term an ASG cannot represent an unoccluded texel (V = 1 over the
// hemisphere: the best fit c * cos(theta) has an RMS error of 0.5), nor the half-space visible from
// a tilted facet; without it, zero bandwidths give exactly c over the hemisphere around z
// (docs/raycast.md has the measured comparison). Xu et al.'s large-bandwidth integral pi /
// sqrt(lambda mu) holds for both forms, since the two agree near the axis.
//
// Parameters ("AsgParams") are axis z, rotation psi of x about z (relative to the Duff et al. basis
// of z, see orthonormal_basis in vec.hpp), lambda, mu and c. The canonical form has lambda >= mu
// and psi in [0, pi) (the lobe is symmetric under x -> -x), which keeps parameter-space distances
// (used by the visibility clustering) meaningful. AsgRecord packs the canonical parameters into 12
// bytes.
//
// Header-only, C++17, standard library only; every function is safe on any finite input (the
// unpacking of a record is safe on arbitrary bytes).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "model/directions.hpp"
#include "model/vec.hpp"

namespace clothbake::model {

// Largest bandwidth a fit may produce and a record can hold. A lobe with lambda = 4096 has a 1/e
// half-width of 1/64 rad, far below the ~0.08 rad bin size of a 32 x 32 hemisphere grid.
inline constexpr double kAsgMaxBandwidth = 4096.0;
// Largest amplitude a record can hold (a least-squares fit of a 0/1 function may overshoot 1).
// Amplitudes are stored in steps of 1/32768 so that 0 and 1 (unoccluded) are exact.
inline constexpr double kAsgMaxAmplitude = 65535.0 / 32768.0;

// An ASG with an explicit frame. Invariant (not checked): x, y, z orthonormal, right-handed.
template <class T>
struct Asg {
  Vec3<T> x{T(1), T(0), T(0)};
  Vec3<T> y{T(0), T(1), T(0)};
  Vec3<T> z{T(0), T(0), T(1)};
  T lambda = T(0);     // bandwidth along x, >= 0
  T mu = T(0);         // bandwidth along y, >= 0
  T amplitude = T(0);  // c >= 0
};

// The parameters the fit and the clustering work with.
template <class T>
struct AsgParams {
  Vec3<T> axis{T(0), T(0), T(1)};  // unit lobe axis z
  T rotation = T(0);               // psi: x = cos(psi) s + sin(psi) t, (s, t) = basis of the axis
  T lambda = T(0);
  T mu = T(0);
  T amplitude = T(0);
};

// G(v) for a unit direction v (any length works for the sign test; bandwidths assume |v| = 1).
template <class T>
inline T asg_eval(const Asg<T>& g, const Vec3<T>& v) {
  T vz = dot(v, g.z);
  if (!(vz > T(0))) return T(0);
  T vx = dot(v, g.x), vy = dot(v, g.y);
  return g.amplitude * std::exp(-g.lambda * vx * vx - g.mu * vy * vy);
}

// The frame of params: x is the Duff et al. basis vector s of the axis rotated by psi about it.
// A zero or non-finite axis is replaced by +z.
template <class T>
inline Asg<T> asg_from_params(const AsgParams<T>& p) {
  Asg<T> g;
  Vec3<T> z = normalize(p.axis);
  if (!(length(z) > T(0.5))) z = {T(0), T(0), T(1)};
  Vec3<T> s, t;
  orthonormal_basis(z, s, t);
  T c = std::cos(p.rotation), sn = std::sin(p.rotation);
  g.z = z;
  g.x = s * c + t * sn;
  g.y = cross(z, g.x);
  g.lambda = std::max(p.lambda, T(0));
  g.mu = std::max(p.mu, T(0));
  g.amplitude = std::max(p.amplitude, T(0));
  return g;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // the bake's and the tools', not shading's (the single file leaves them out)
// Canonical parameters of g: lambda >= mu (x and y swapped if needed), psi in [0, pi); psi = 0 when
// the lobe is isotropic (lambda == mu), where the rotation has no meaning.
template <class T>
inline AsgParams<T> asg_to_params(const Asg<T>& g) {
  AsgParams<T> p;
  p.axis = normalize(g.z);
  p.lambda = g.lambda;
  p.mu = g.mu;
  p.amplitude = g.amplitude;
  Vec3<T> x = g.x;
  if (p.lambda < p.mu) {
    std::swap(p.lambda, p.mu);
    x = g.y;
  }
  if (p.lambda == p.mu) {
    p.rotation = T(0);
    return p;
  }
  Vec3<T> s, t;
  orthonormal_basis(p.axis, s, t);
  T psi = std::atan2(dot(x, t), dot(x, s));  // (-pi, pi]
  if (psi < T(0)) psi += kPi<T>;
  if (psi >= kPi<T>) psi -= kPi<T>;
  p.rotation = psi;
  return p;
}

// g(k) = integral_0^1 exp(-k (1 - t^2)) dt for k >= 0 (the polar integral of an ASG along one
// azimuth; equals Dawson's function F(sqrt k) / sqrt k). Relative accuracy ~1e-15.
inline double asg_polar_integral(double k) {
  if (!(k > 0.0)) return 1.0;
  if (k <= 40.0) {
    // e^-k sum_n k^n / (n! (2n + 1)): every term positive, so no cancellation.
    double term = std::exp(-k), sum = term;
    for (int n = 1; n < 400; ++n) {
      term *= k / double(n);
      double add = term / double(2 * n + 1);
      sum += add;
      if (double(n) > k && add < 1e-17 * sum) break;
    }
    return sum;
  }
  // Asymptotic series 1/(2k) sum_m (2m-1)!! / (2k)^m; the neglected remainder is O(e^-k).
  double inv = 1.0 / (2.0 * k), term = 1.0, sum = 1.0;
  for (int m = 1; m < 60; ++m) {
    term *= double(2 * m - 1) * inv;
    sum += term;
    if (term < 1e-17 * sum) break;
  }
  return sum * inv;
}

// Integral of G over the sphere, in sr times the amplitude: c * int_0^2pi g(lambda cos^2 phi + mu
// sin^2 phi) dphi, the azimuthal integral by the periodic trapezoid rule (exponentially convergent;
// the node count grows with the anisotropy so that the peak near the narrow axis is resolved).
// Relative accuracy better than 1e-9 for bandwidths up to kAsgMaxBandwidth (tests/asg checks it
// against quadrature over the sphere). 2 pi c at zero bandwidths.
template <class T>
inline T asg_integral(const Asg<T>& g) {
  const double lambda = std::max(double(g.lambda), 0.0), mu = std::max(double(g.mu), 0.0);
  const double hi = std::max(lambda, mu), lo = std::min(lambda, mu);
  const double ratio = std::sqrt((hi + 1.0) / (lo + 1.0));
  const int nodes = int(std::clamp(std::ceil(24.0 * ratio) * 4.0, 64.0, 16384.0));
  // phi in [0, pi/2] with the 4-fold symmetry of cos^2/sin^2: midpoint nodes of the periodic rule.
  double sum = 0.0;
  for (int i = 0; i < nodes; ++i) {
    double phi = (double(i) + 0.5) * (kPi<double> / 2) / double(nodes);
    double c = std::cos(phi), s = std::sin(phi);
    sum += asg_polar_integral(lambda * c * c + mu * s * s);
  }
  return T(double(g.amplitude) * 2.0 * kPi<double> * sum / double(nodes));
}

// Xu et al.'s closed-form approximation for sharp lobes: c pi / sqrt(lambda mu); relative error
// O(1 / min(lambda, mu)). Infinite when a bandwidth is zero.
template <class T>
inline T asg_integral_sharp(const Asg<T>& g) {
  return g.amplitude * kPi<T> / std::sqrt(g.lambda * g.mu);
}
#endif

// 12-byte record of canonical ASG parameters (little-endian uint16 fields on disk):
//   axis_u, axis_v : the axis on the equal-area hemisphere square (DirectionGrid min_cos 0),
//                    u = axis_u / 65535 (axes below the horizon are stored on the rim)
//   rotation       : psi = rotation * pi / 65536, in [0, pi)
//   lambda, mu     : bandwidth = kAsgMaxBandwidth * (q / 65535)^2 (square-root code: relative
//                    precision where small bandwidths need it)
//   amplitude      : c = q / 32768 (so 1 is exact), in [0, kAsgMaxAmplitude]
// Quantisation changes G by at most ~2e-3 (tests/asg measures it).
struct AsgRecord {
  uint16_t axis_u = 32768, axis_v = 32768;
  uint16_t rotation = 0;
  uint16_t lambda = 0, mu = 0;
  uint16_t amplitude = 0;
};
static_assert(sizeof(AsgRecord) == 12, "AsgRecord is a 12-byte on-disk record");
static_assert(alignof(AsgRecord) == 2, "AsgRecord has 2-byte alignment");

#ifndef CLOTHBAKE_SINGLE_FILE  // the bake's and the tools', not shading's (the single file leaves them out)
namespace detail {
inline uint16_t quantize_unit(double x) {  // [0, 1] -> [0, 65535], NaN -> 0
  if (!(x > 0.0)) return 0;
  if (x >= 1.0) return 65535;
  return uint16_t(std::lround(x * 65535.0));
}
}  // namespace detail

// Packs params (canonicalised first through an Asg); values are clamped into the record's ranges.
template <class T>
inline AsgRecord pack_asg(const AsgParams<T>& params) {
  AsgParams<double> p = asg_to_params(asg_from_params(
      AsgParams<double>{Vec3d(params.axis), double(params.rotation), double(params.lambda),
                        double(params.mu), double(params.amplitude)}));
  AsgRecord r;
  DirectionGrid<double> hemisphere{1, 0.0};
  double u, v;
  hemisphere.to_square(p.axis, u, v);
  r.axis_u = detail::quantize_unit(u);
  r.axis_v = detail::quantize_unit(v);
  long q = std::lround(p.rotation / kPi<double> * 65536.0);
  r.rotation = uint16_t(((q % 65536) + 65536) % 65536);
  r.lambda = detail::quantize_unit(std::sqrt(std::max(p.lambda, 0.0) / kAsgMaxBandwidth));
  r.mu = detail::quantize_unit(std::sqrt(std::max(p.mu, 0.0) / kAsgMaxBandwidth));
  r.amplitude = detail::quantize_unit(p.amplitude / kAsgMaxAmplitude);  // = round(c * 32768)
  return r;
}
#endif

// Any 12 bytes give a valid lobe (finite, bandwidths in range).
template <class T>
inline AsgParams<T> unpack_asg(const AsgRecord& r) {
  DirectionGrid<double> hemisphere{1, 0.0};
  Vec3d axis = hemisphere.direction(r.axis_u / 65535.0, r.axis_v / 65535.0);
  double sl = r.lambda / 65535.0, sm = r.mu / 65535.0;
  AsgParams<T> p;
  p.axis = Vec3<T>(axis);
  p.rotation = T(r.rotation * kPi<double> / 65536.0);
  p.lambda = T(kAsgMaxBandwidth * sl * sl);
  p.mu = T(kAsgMaxBandwidth * sm * sm);
  p.amplitude = T(r.amplitude / 32768.0);
  return p;
}

}  // namespace clothbake::model

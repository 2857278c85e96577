// Decoders of the 16-bit codes of the feature maps height, tangent, normal, gap and albedo (which
// map_entropy.hpp codes losslessly; docs/format.md, "Feature maps"; docs/performance.md "Asset
// sizes" says why these encodings). The encoders are the writer's (formats/writer/
// map_encoding.hpp); both sides share the constants below.
//
//   height  1 code per texel    IEEE 754 binary16, round to nearest even: |error| <= 2^-11 |h|
//                               (2^-25 below 2^-14)
//   tangent 2 codes per texel   octahedral unit vector, snorm16: a = max(q / 32767, -1)
//   normal  2 codes per texel   the same
//   gap     1 code per texel    unorm16: I = q / 65535 (0 and 1 exact)
//   albedo  3 codes per texel   unorm16 per channel
//
// Octahedral map (Meyer et al. 2010, "On floating-point normal vectors"; Cigolle et al. 2014):
// (a, b) in [-1, 1]^2 (a = max(q / 32767, -1) in double) decodes to v = (a, b, 1 - |a| - |b|);
// where that z < 0 the outer triangles fold back: (x, y) = ((1 - |b|) sign(a), (1 - |a|) sign(b)),
// with sign(0) = +1; then v / |v|, computed in double and rounded to float once per component. |x|
// + |y| + |z| = 1, so |v| >= 1/sqrt(3) and every code pair decodes to a unit vector (any bytes are
// valid). 0, +-1 are exact codes, so the axes (0, 0, +-1), (+-1, 0, 0), (0, +-1, 0) round-trip
// exactly.
//
// C++17, standard library only, header-only, noexcept; safe on any input.
#pragma once

#include <cmath>
#include <cstdint>

namespace clothbake::reader {

inline constexpr float kSnorm16Scale = 32767.0f;
inline constexpr float kUnorm16Scale = 65535.0f;

inline float unorm16_to_float(uint16_t q) noexcept {
  return float(q) / kUnorm16Scale;
}

// The unit vector of octahedral coordinates (a, b) in [-1, 1]^2 (values outside are clamped), in
// double (the writer compares candidate codes with it: their angles differ by about 1e-5 rad,
// which float components could not resolve).
inline void octahedral_to_unit(double a, double b, double out[3]) noexcept {
  a = a < -1.0 ? -1.0 : (a > 1.0 ? 1.0 : a);
  b = b < -1.0 ? -1.0 : (b > 1.0 ? 1.0 : b);
  double x = a, y = b;
  const double z = 1.0 - std::fabs(x) - std::fabs(y);
  if (z < 0.0) {
    x = (1.0 - std::fabs(b)) * (a >= 0.0 ? 1.0 : -1.0);
    y = (1.0 - std::fabs(a)) * (b >= 0.0 ? 1.0 : -1.0);
  }
  const double inv = 1.0 / std::sqrt(x * x + y * y + z * z);
  out[0] = x * inv;
  out[1] = y * inv;
  out[2] = z * inv;
}

// The snorm16 value of a stored code, in double (exactly q / 32767 rounded once).
inline double snorm16_to_double(int16_t q) noexcept {
  const double a = double(q) / 32767.0;
  return a < -1.0 ? -1.0 : a;
}

// One stored octahedral texel (two snorm16 codes) to its unit vector.
inline void decode_octahedral(const int16_t code[2], float out[3]) noexcept {
  double v[3];
  octahedral_to_unit(snorm16_to_double(code[0]), snorm16_to_double(code[1]), v);
  out[0] = float(v[0]);
  out[1] = float(v[1]);
  out[2] = float(v[2]);
}

}  // namespace clothbake::reader

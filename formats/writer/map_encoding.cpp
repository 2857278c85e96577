#include "formats/writer/map_encoding.hpp"

#include <cmath>

#include "formats/reader/map_encoding.hpp"

namespace clothbake::formats {

uint16_t float_to_unorm16(float x) {
  const double c = x > 0.0f ? (x < 1.0f ? double(x) : 1.0) : 0.0;  // NaN -> 0
  return uint16_t(std::lround(c * 65535.0));
}

void unit_to_octahedral(const float v[3], int16_t out[2]) {
  const double x = v[0], y = v[1], z = v[2];
  const double l1 = std::fabs(x) + std::fabs(y) + std::fabs(z);
  if (!(l1 > 0.0)) {
    out[0] = out[1] = 0;
    return;
  }
  double a = x / l1, b = y / l1;
  if (z < 0.0) {
    const double fa = (1.0 - std::fabs(b)) * (a >= 0.0 ? 1.0 : -1.0);
    const double fb = (1.0 - std::fabs(a)) * (b >= 0.0 ? 1.0 : -1.0);
    a = fa;
    b = fb;
  }
  const double len = std::sqrt(x * x + y * y + z * z);
  const double ux = x / len, uy = y / len, uz = z / len;
  const double sa = std::floor(a * reader::kSnorm16Scale),
               sb = std::floor(b * reader::kSnorm16Scale);
  double best = -2.0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const double qa = std::fmin(std::fmax(sa + i, -32767.0), 32767.0);
      const double qb = std::fmin(std::fmax(sb + j, -32767.0), 32767.0);
      const int16_t code[2] = {int16_t(qa), int16_t(qb)};
      double d[3];  // in double: the candidates' dot products differ by about 1e-10
      reader::octahedral_to_unit(reader::snorm16_to_double(code[0]),
                                 reader::snorm16_to_double(code[1]), d);
      const double dot = d[0] * ux + d[1] * uy + d[2] * uz;
      if (dot > best) {
        best = dot;
        out[0] = code[0];
        out[1] = code[1];
      }
    }
}

}  // namespace clothbake::formats

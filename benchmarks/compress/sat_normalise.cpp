// SAT normalisation (sat_normalise.hpp).
#include "benchmarks/compress/sat_normalise.hpp"

#include <algorithm>

namespace clothbake::compress {

const char* sat_normalisation_name(SatNormalisation mode) {
  switch (mode) {
    case SatNormalisation::None:
      return "none";
    case SatNormalisation::Plane:
      return "plane";
    case SatNormalisation::PlaneUnit:
      return "plane+unit";
  }
  return "?";
}

void summed_area_table(const float* table, int n, double* sat) {
  const std::size_t side = std::size_t(n);
  for (std::size_t y = 0; y < side; ++y) {
    double row = 0.0;
    for (std::size_t x = 0; x < side; ++x) {
      row += double(table[y * side + x]);
      sat[y * side + x] = row + (y > 0 ? sat[(y - 1) * side + x] : 0.0);
    }
  }
}

SatTransform normalise_sat(const double* sat, int n, SatNormalisation mode, float* out) {
  const std::size_t side = std::size_t(n), count = side * side;
  SatTransform t;
  if (count == 0) return t;
  t.mean = sat[count - 1] / double(count);
  t.plane = mode != SatNormalisation::None;
  auto deviation = [&](std::size_t x, std::size_t y) {
    return sat[y * side + x] - (t.plane ? t.mean * double(x + 1) * double(y + 1) : 0.0);
  };
  if (mode == SatNormalisation::PlaneUnit) {
    double lo = deviation(0, 0), hi = lo;
    for (std::size_t y = 0; y < side; ++y)
      for (std::size_t x = 0; x < side; ++x) {
        lo = std::min(lo, deviation(x, y));
        hi = std::max(hi, deviation(x, y));
      }
    t.offset = lo;
    t.scale = hi > lo ? hi - lo : 1.0;
  }
  for (std::size_t y = 0; y < side; ++y)
    for (std::size_t x = 0; x < side; ++x)
      out[y * side + x] = float((deviation(x, y) - t.offset) / t.scale);
  return t;
}

}  // namespace clothbake::compress

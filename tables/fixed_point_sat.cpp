// Exact fixed-point SAT construction (fixed_point_sat.hpp).
#include "tables/fixed_point_sat.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common/error.hpp"

namespace clothbake::tables {
namespace {

constexpr double kTwo32 = 4294967296.0;
constexpr double kTwo62 = 4611686018427387904.0;

double scale_for(int resolution, double total, int bits) {
  const double texels = double(resolution) * double(resolution);
  const double range = bits == 32 ? kTwo32 - 1.0 - texels : kTwo62;
  return range / total;
}

// Adds the running row sums to the row above, column by column (restrict: lets the compiler
// vectorise across the interleaved cluster columns).
template <class E>
inline void add_row(std::size_t count, const E* __restrict__ up, const E* __restrict__ row,
                    E* __restrict__ cell) {
  for (std::size_t c = 0; c < count; ++c)
    cell[c] = up[c] + row[c];
}

template <class E>
void build(int n, std::span<const float> values, std::span<const int16_t> column,
           std::span<const double> scale, E* out) {
  const std::size_t columns = scale.size();
  std::vector<E> row(columns);
  for (int y = 0; y < n; ++y) {
    std::fill(row.begin(), row.end(), E(0));
    E* dst = out + std::size_t(y) * std::size_t(n) * columns;
    const E* above = y > 0 ? dst - std::size_t(n) * columns : nullptr;
    const float* v = values.data() + std::size_t(y) * std::size_t(n);
    const int16_t* col = column.data() + std::size_t(y) * std::size_t(n);
    for (int x = 0; x < n; ++x) {
      const int k = col[x];
      // The integer fits E: value * scale <= the range of scale_for.
      if (k >= 0) row[std::size_t(k)] += E(fixed_point_quantise(v[x], scale[std::size_t(k)]));
      E* cell = dst + std::size_t(x) * columns;
      if (above)
        add_row(columns, above + std::size_t(x) * columns, row.data(), cell);
      else
        std::copy(row.begin(), row.end(), cell);
    }
  }
}

}  // namespace

double sat_relative_error_bound(int resolution, int element_bits) {
  const double texels = double(resolution) * double(resolution);
  const double range = element_bits == 32 ? kTwo32 - 1.0 - texels : kTwo62;
  return texels / (2.0 * range);
}

int sat_element_bits(int resolution, double max_relative_error) {
  const double texels = double(resolution) * double(resolution);
  if (texels < kTwo32 / 2 && sat_relative_error_bound(resolution, 32) <= max_relative_error)
    return 32;
  return 64;
}

void fixed_point_scales(int resolution, std::span<const double> totals, int element_bits,
                        double* scales, double* units) {
  for (std::size_t k = 0; k < totals.size(); ++k) {
    if (!(totals[k] > 0.0) || !std::isfinite(totals[k]))
      throw_internal_error("fixed-point SAT: column " + std::to_string(k) + " total " +
                           std::to_string(totals[k]) + " is not finite and positive");
    scales[k] = scale_for(resolution, totals[k], element_bits);
    units[k] = 1.0 / scales[k];
  }
}

void build_fixed_point_sat(int resolution, std::span<const float> values,
                           std::span<const int16_t> column, std::span<const double> totals,
                           int element_bits, double* units, void* out) {
  std::vector<double> scale(totals.size());
  fixed_point_scales(resolution, totals, element_bits, scale.data(), units);
  if (element_bits == 32)
    build(resolution, values, column, scale, static_cast<uint32_t*>(out));
  else
    build(resolution, values, column, scale, static_cast<uint64_t*>(out));
}

}  // namespace clothbake::tables

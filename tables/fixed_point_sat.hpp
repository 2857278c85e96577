// Exact fixed-point summed-area tables (docs/tables.md, "Precision").
//
// A table's non-negative texel values T (one bin, several cluster columns interleaved per texel)
// are quantised per column to integers q = round(T * scale) with
//   u32: scale = (2^32 - 1 - N^2) / sum(T),   u64: scale = 2^62 / sum(T),
// so the tile's integer total stays below 2^32 (2^62) whatever the rounding. The SAT of the
// integers is built with integer additions: exact, no cancellation, independent of the order of
// summation. A rectangle sum read back is therefore exact up to the texels' own quantisation,
// |error| <= A * unit / 2 for A texels with unit = 1 / scale = sum(T) / (2^32 - 1 - N^2): relative
// to the table's mean texel value m = sum(T) / N^2, at most N^2 / (2 (2^32 - 1 - N^2)) per texel,
// 7.6e-6 at 256^2 for u32 -- anywhere in the table, the far corner included. Double SATs stored
// as float would have an error of float's epsilon times the running sum instead (~1e-2 m at the
// far corner of a 256^2 table).
//
// C++20; the functions are pure and never throw except as documented.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace clothbake::tables {

// Element width meeting `max_relative_error` (relative to the mean texel value) at resolution N:
// 32 when N^2 / (2 (2^32 - 1 - N^2)) <= max_relative_error, else 64.
int sat_element_bits(int resolution, double max_relative_error);

// Worst-case quantisation error of one texel relative to the mean texel value, for N and bits.
double sat_relative_error_bound(int resolution, int element_bits);

// Builds the interleaved SAT of one bin. values: N * N floats (row-major), column: per texel the
// stored column its value belongs to (-1: the texel belongs to no stored column, its value must be
// 0 or is ignored), totals: per column the sum of its values (double, > 0 for every column),
// columns: C. Writes units[k] = 1 / scale_k and out[(y * N + x) * C + k] (uint32_t or uint64_t
// per element_bits). Throws Error(Internal) for a column total that is not finite and positive.
void build_fixed_point_sat(int resolution, std::span<const float> values,
                           std::span<const int16_t> column, std::span<const double> totals,
                           int element_bits, double* units, void* out);

// The per-column scales and units (1 / scale) that build_fixed_point_sat uses for these totals:
// the same formula and the same check (Error(Internal) for a total that is not finite and
// positive). scales and units: totals.size() doubles each.
void fixed_point_scales(int resolution, std::span<const double> totals, int element_bits,
                        double* scales, double* units);

// One texel's stored integer, q = round-half-up(value * scale), exactly as build_fixed_point_sat
// adds it to the SAT (value >= 0). A rectangle of one texel read back from the SAT gives q
// exactly, so q * unit is the value a raw table returns for the texel.
inline uint64_t fixed_point_quantise(float value, double scale) {
  // A truncating conversion (values are >= 0): no libm call in the fill loops.
  return uint64_t(double(value) * scale + 0.5);
}

}  // namespace clothbake::tables

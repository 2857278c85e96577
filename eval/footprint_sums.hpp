// Summed-area tables of the per-texel quantities the evaluator's control variates integrate and
// that no Integral-Radiance table holds (docs/evaluator.md, "Footprint sums"):
//
//   k(x)              = the specular albedo of x's yarn times x's colour (RGB): the k-bar of Eq. 9
//   A_c(x)            = [label(x) = c]                            (sheen; cluster areas)
//   Rd_c(x), Td_c(x)  = I(x) R_d(x) [label(x) = c], I(x) T_d(x) [label(x) = c]  (RGB, diffuse)
//   G_c(x)            = (1 - I(x)) [label(x) = c]                (delta, when the asset has no gap
//                                                                table)
//
// One exclusive prefix sum in double per channel, interleaved by channel at every SAT point, so
// that a footprint reads each corner's channels from consecutive memory. A footprint integral is
// exact up to double rounding (relative error ~1e-16 times the number of texels), for any
// rectangle: the plan of reader::make_footprint_plan reduces it to one tile, and a fractional
// corner is the bilinear interpolation of the prefix sums (exact for piecewise-constant texels).
//
// C++17, standard library only. build() allocates (N + 1)^2 x channels doubles from the given
// allocator (model/memory.hpp); integral() does not allocate and is noexcept.
#pragma once

#include <cstdint>

#include "formats/reader/radiance_query.hpp"
#include "model/memory.hpp"

namespace clothbake::eval {

// Channel layout of the footprint sums for C clusters.
struct SumChannels {
  uint32_t clusters = 0;
  uint32_t albedo() const { return 0; }                    // 3
  uint32_t area() const { return 3; }                      // C
  uint32_t diffuse_r() const { return 3 + clusters; }      // 3C, [c][rgb]
  uint32_t diffuse_t() const { return 3 + 4 * clusters; }  // 3C
  uint32_t gap() const { return 3 + 7 * clusters; }        // C
  uint32_t count() const { return 3 + 8 * clusters; }
};

class FootprintSums {
 public:
  // Builds the tables from per-texel values: values(t, out) writes count() channels of texel t
  // (t = y * N + x). Returns false when `allocator` (the default one when null) gives no memory.
  template <class TexelChannels>
  bool build(uint32_t n, SumChannels layout, TexelChannels values,
             const model::Allocator* allocator = nullptr) noexcept;
  // The same for any `channels` channels (layout() is then empty): the block-mean parallax depths.
  template <class TexelChannels>
  bool build(uint32_t n, uint32_t channels, TexelChannels values,
             const model::Allocator* allocator = nullptr) noexcept;

  bool empty() const { return n_ == 0; }
  uint32_t resolution() const { return n_; }
  const SumChannels& layout() const { return layout_; }
  uint64_t bytes() const { return uint64_t(prefix_.size()) * sizeof(double); }

  // Integral over the planned footprint of channels [first, first + count) into out[0..count).
  void integral(const reader::FootprintPlan& plan, uint32_t first, uint32_t count,
                double* out) const noexcept;

 private:
  // Adds weight * I(x, y) of the channels to out, I the integral over [0, x) x [0, y).
  void add_prefix(double x, double y, double weight, uint32_t first, uint32_t count,
                  double* out) const noexcept;
  const double* point(uint32_t i, uint32_t j) const {
    return prefix_.data() + (uint64_t(j) * (n_ + 1) + i) * stride_;
  }

  uint32_t n_ = 0;
  uint32_t stride_ = 0;
  SumChannels layout_;
  model::Buffer<double> prefix_;  // (N + 1) x (N + 1) x stride, exclusive prefix sums
};

template <class TexelChannels>
bool FootprintSums::build(uint32_t n, SumChannels layout, TexelChannels values,
                          const model::Allocator* allocator) noexcept {
  if (!build(n, layout.count(), values, allocator)) return false;
  layout_ = layout;
  return true;
}

template <class TexelChannels>
bool FootprintSums::build(uint32_t n, uint32_t channels, TexelChannels values,
                          const model::Allocator* allocator) noexcept {
  const uint32_t stride = channels;
  const uint64_t points = uint64_t(n + 1) * (n + 1);
  model::Buffer<double> prefix, texel, row;  // zero-filled
  if (!prefix.allocate(points * stride, allocator) || !texel.allocate(stride, allocator) ||
      !row.allocate(stride, allocator))
    return false;
  // prefix[j][i] = sum over y < j, x < i: row by row, a running row sum plus the row above.
  for (uint32_t y = 0; y < n; ++y) {
    for (double& r : row)
      r = 0.0;
    for (uint32_t x = 0; x < n; ++x) {
      values(uint64_t(y) * n + x, texel.data());
      const double* above = prefix.data() + (uint64_t(y) * (n + 1) + x + 1) * stride;
      double* here = prefix.data() + (uint64_t(y + 1) * (n + 1) + x + 1) * stride;
      for (uint32_t c = 0; c < stride; ++c) {
        row[c] += texel[c];
        here[c] = above[c] + row[c];
      }
    }
  }
  n_ = n;
  stride_ = stride;
  layout_ = SumChannels{};
  prefix_ = std::move(prefix);
  return true;
}

}  // namespace clothbake::eval

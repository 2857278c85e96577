// Whole-tile push-forward sums of the multi-scale control variate, per parallax view bin
// (docs/evaluator.md, "Unbiased multi-scale").
//
// The control variate g of the unbiased form is evaluated at the sample's own destination
// x'_k(p) (view bin k), so its exact mean over a footprint is (1/|P|) sum_t W_P(t) g(t), the
// push-forward of P. Over one whole period of the tile (any N x N window: every source texel once)
// that weight is the bin's multiplicity
//
//   m_k(t) = sum_q area((q + delta_kq) ∩ t),   delta_kq = r_k(q) N (v_kx, v_ky) / v_kz,
//
// (q the unit square of source texel q, v_k the bin's centre direction, sum_t m_k(t) = N^2), and g
// is linear in a fixed set of per-texel channels with per-estimate coefficients. So the tile's sum
// of g is a dot product of the per-estimate coefficients with
//
//   S_k[ch] = sum_t m_k(t) channel_ch(t),
//
// channels (M the rank of the visibility basis, e_0 = 1, e_1..e_M the texel's basis coefficients):
//   spec(i, j)   = e_j(t) w_i(t)            for every compressed image i (w_i(t) the texel's weight
//                                          for image i: 1 for its cell mean, its stored
//                                          coefficient for a basis image, 0 for other cells)
//   lobe(c, j)+0..2 = e_j(t) I(t) R_d(t)    [c(t) = c], RGB (R_d = the yarn's times the colour)
//   lobe(c, j)+3..5 = e_j(t) I(t) T_d(t)    [c(t) = c], RGB
//   lobe(c, j)+6    = e_j(t)               [c(t) = c]   (sheen)
//   lobe(c, j)+7    = e_j(t) (1 - I(t))    [c(t) = c]   (delta transmission)
//
// Each bin's sums are built on its first bin_sums() call (thread-safe, std::call_once; the
// estimator asks for a view's four bins on the view's first estimate): one pass over the N^2
// source texels to splat m_k, one over the destinations. Memory: count() doubles per bin built
// (about 10 KB for the default twill), cost 6-9 ms per bin at N = 256 (docs/evaluator.md).
//
// C++17, standard library only. bin_sums() allocates only on a bin's first use.
#pragma once

#include <cstdint>
#include <mutex>

#include "model/memory.hpp"

namespace clothbake::eval {

struct EvalData;

// Channel layout of the push-forward sums.
struct PushforwardChannels {
  uint32_t images = 0;    // compressed images of the specular tables
  uint32_t clusters = 0;  // visibility clusters
  uint32_t rank = 0;      // M: visibility basis components besides the mean
  static constexpr uint32_t kPerLobeGroup = 8;
  uint32_t spec(uint32_t image, uint32_t j) const { return image * (rank + 1) + j; }
  uint32_t lobe(uint32_t cluster, uint32_t j) const {
    return images * (rank + 1) + (cluster * (rank + 1) + j) * kPerLobeGroup;
  }
  uint32_t count() const { return (images + clusters * kPerLobeGroup) * (rank + 1); }
};

class PushforwardSums {
 public:
  // Binds the sums to an open evaluator's data (which must outlive this) with `bins` parallax view
  // bins. Returns false when the per-bin bookkeeping cannot be allocated.
  bool init(const EvalData* data, uint32_t bins, const PushforwardChannels& layout) noexcept;
  const PushforwardChannels& layout() const noexcept { return layout_; }

  // The count() sums of view bin `bin` (< bins), built on first use; null when they cannot be
  // allocated. Precondition: the bin is covered by the parallax table (planned assets).
  const double* bin_sums(uint32_t bin) const noexcept;

 private:
  void build(uint32_t bin) const noexcept;

  const EvalData* data_ = nullptr;
  PushforwardChannels layout_;
  mutable model::Buffer<std::once_flag> once_;
  mutable model::Buffer<model::Buffer<double>> sums_;
};

}  // namespace clothbake::eval

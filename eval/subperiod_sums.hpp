// Block push-forward sums of the multi-scale control variate, per parallax view bin: the exact
// integral of g under the parallax push-forward over any rectangle of whole source blocks
// (docs/evaluator.md, "Unbiased multi-scale", "Footprints below a period").
//
// The tile of N x N source texels is cut into nb x nb blocks of B = N / nb texels. In view bin k a
// source texel q moves rigidly by delta_kq (Eq. 2 at the bin's centre direction, as
// pushforward_sums.hpp), so the integral of g(x'_k(p)) over a source block b is
//
//   S_k[b] = sum_{q in b} sum_t area((q + delta_kq) ∩ t) channels(t),
//
// a vector of per-texel channels (the layout of PushforwardChannels at visibility rank r <= M)
// with per-estimate coefficients. These sums keep, per bin, the exclusive 2-D prefix sums over the
// block grid,
//
//   prefix_k(i, j) = sum over blocks (bx, by) with bx < i, by < j of S_k[(bx, by)],
//                    i, j in [0, nb], (nb + 1)^2 points of count() doubles each,
//
// so that the integral over any block-aligned source rectangle (in block units, anywhere: the tile
// wraps) is a signed sum of at most 9 prefix points (reader::FootprintPlan in block units, whose
// corners are then grid points) and its dot product with the estimate's coefficients. The whole
// tile is prefix_k(nb, nb): the whole-tile sums of pushforward_sums.hpp at rank r.
//
// Each bin's prefix sums are built on its first bin_prefix() call (thread-safe, std::call_once):
// one pass over the N^2 source texels splatting each moved unit square's channels onto the block
// accumulator (about 4 (images of the texel's cell + 8) (r + 1) multiply-adds per texel), then
// the prefix pass. Memory: (nb + 1)^2 count() doubles per bin built; the evaluator chooses nb at
// open so that every bin of the table together stays within EvalOptions::max_block_sum_bytes.
//
// C++17, standard library only. bin_prefix() allocates only on a bin's first use; a failed
// allocation is reported as null (the estimate then answers Unsupported), never thrown.
#pragma once

#include <cstdint>
#include <mutex>

#include "eval/pushforward_sums.hpp"

namespace clothbake::eval {

struct EvalData;

class SubperiodSums {
 public:
  // Binds the sums to an open evaluator's data (which must outlive this and whose control-variate
  // records are built) for `bins` parallax view bins, channels `layout` (its rank r is the
  // visibility rank the block sums hold) and nb = `blocks` blocks per side (nb >= 1 divides N).
  // Returns false when the per-bin bookkeeping cannot be allocated.
  bool init(const EvalData* data, uint32_t bins, const PushforwardChannels& layout,
            uint32_t blocks) noexcept;
  bool is_open() const noexcept { return blocks_ != 0; }
  const PushforwardChannels& layout() const noexcept { return layout_; }
  uint32_t blocks() const noexcept { return blocks_; }
#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
  // Bytes of one bin's prefix sums.
  uint64_t bin_bytes() const noexcept;
#endif

  // The (nb + 1)^2 x count() prefix sums of view bin `bin` (< bins), point (i, j) at
  // (j (nb + 1) + i) count(); built on first use; null when they cannot be allocated.
  // Precondition: the bin is covered by the parallax table (planned assets).
  const float* bin_prefix(uint32_t bin) const noexcept;

 private:
  void build(uint32_t bin) const noexcept;

  const EvalData* data_ = nullptr;
  PushforwardChannels layout_;
  uint32_t blocks_ = 0;
  mutable model::Buffer<std::once_flag> once_;
  mutable model::Buffer<model::Buffer<float>> prefix_;
};

}  // namespace clothbake::eval

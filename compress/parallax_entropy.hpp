// The block coder's encoder: one plane of byte symbols predicted (LOCO-I median edge detector or
// the tile's repeat shift) and coded with static rANS (the block format and the decoder:
// formats/reader/parallax_entropy.hpp; docs/format.md, "The block coder"). The feature maps
// (compress/map_entropy.hpp) code their byte planes with it, the hierarchical parallax
// (compress/parallax_hierarchy.hpp) and the coded C-PCA coefficients (coefficient_coding.hpp) use
// its rANS and frequency helpers.
//
// Deterministic: the shift search runs rows of shifts in parallel (TBB) and concatenates them in
// order, so its result does not depend on the thread count. C++20.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace clothbake::compress {

// Counts of 256 symbols scaled to frequencies summing to 4096 (reader::kRansScale), every present
// symbol at least 1 (all 0 when no symbol is present). Deterministic.
void normalise_frequencies(const uint64_t* counts, uint16_t* freq);
// Appends one block in the format of reader::decode_parallax_block and its hierarchical sibling:
// the 8-byte header (sx, sy, group, flags 0), then the rANS coding of the `count` symbols sym[i]
// in contexts ctx[i] with the frequency tables `freq` (256 per context; every coded symbol must
// have a non-zero frequency, else Error(Internal)).
void rans_encode_block(uint32_t sx, uint32_t sy, uint32_t group, const uint8_t* ctx,
                       const uint8_t* sym, std::size_t count, const uint16_t* freq,
                       std::vector<uint8_t>& out);
// Residual counts of a plane with shift (sx, sy): 5 x 256 values.
std::vector<uint64_t> parallax_residual_counts(const uint8_t* plane, uint32_t n, uint32_t sx,
                                               uint32_t sy);
// 5 x 256 frequencies summing to 4096 per context (0 for an unused context) from counts.
std::vector<uint16_t> parallax_frequencies(const std::vector<uint64_t>& counts);
// Encodes one plane (n * n codes) with shift (sx, sy) ((0, 0): none) as a block of `group`, whose
// tables `freq` (5 x 256) must give every residual of the plane a non-zero frequency. Exposed for
// tests.
std::vector<uint8_t> encode_parallax_block(const uint8_t* plane, uint32_t n, uint32_t sx,
                                           uint32_t sy, uint32_t group, const uint16_t* freq);

// The candidate shifts of a plane: up to `count` shifts (sx, sy), sy in [1, N) or sy = 0 and sx
// in [1, N), whose exact-repeat share over a 1/4 x 1/4 subsample is at least 1/2, best first.
// Shifts whose toroidal length max(min(sx, N - sx), min(sy, N - sy)) is below `min_length` are
// not considered (a piecewise-constant map repeats almost everywhere at a shift of one texel).
std::vector<std::pair<uint32_t, uint32_t>> parallax_shift_candidates(const uint8_t* plane,
                                                                     uint32_t n, int count = 3,
                                                                     uint32_t min_length = 1);

// Shannon estimate, in bits, of coding residuals with these counts (rows of 256, one per context,
// as parallax_residual_counts returns): the sum over contexts of −k log2(k / row total).
double residual_entropy_bits(const std::vector<uint64_t>& counts);

// A block's tile-repeat shift: (0, 0) or one of `candidates`, whichever gives the fewest
// estimated bits (residual_entropy_bits of counts(sx, sy); the first on ties), with its counts.
struct ShiftChoice {
  uint32_t sx = 0, sy = 0;
  std::vector<uint64_t> counts;
};
template <class Counts>
ShiftChoice choose_shift(const std::vector<std::pair<uint32_t, uint32_t>>& candidates,
                         Counts&& counts) {
  ShiftChoice best{0, 0, counts(0u, 0u)};
  double best_bits = residual_entropy_bits(best.counts);
  for (const auto& [sx, sy] : candidates) {
    std::vector<uint64_t> c = counts(sx, sy);
    const double bits = residual_entropy_bits(c);
    if (bits < best_bits) {
      best_bits = bits;
      best = {sx, sy, std::move(c)};
    }
  }
  return best;
}

}  // namespace clothbake::compress

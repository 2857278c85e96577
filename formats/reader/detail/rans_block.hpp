// The block header and decoder tables shared by the block coder's blocks (parallax_entropy.hpp,
// 5 contexts: the feature maps) and the compressed parallax (parallax_hierarchy.hpp, 23
// contexts): internal to the reader library (not installed).
//
// C++17, standard library only, noexcept, no allocation; safe on any bytes (every read is checked
// against `size`).
#pragma once

#include <cstdint>
#include <cstring>

#include "formats/reader/parallax_entropy.hpp"

namespace clothbake::reader::detail {

// A block's header (u16 sx, u16 sy, u16 group, u16 flags = 0) and the coder's initial state.
struct RansBlockStart {
  uint32_t sx = 0, sy = 0, group = 0;
  uint32_t state = 0;
};

// Reads and checks the header of a block of `size` bytes for an n x n plane and `groups` table
// groups; nullptr on success, else what is wrong.
inline const char* read_rans_block_start(const uint8_t* block, uint64_t size, uint32_t n,
                                         uint32_t groups, RansBlockStart* out) noexcept {
  if (size < kEntropyBlockHeader + 4) return "shorter than its header";
  uint16_t sx, sy, group, flags;
  std::memcpy(&sx, block, 2);
  std::memcpy(&sy, block + 2, 2);
  std::memcpy(&group, block + 4, 2);
  std::memcpy(&flags, block + 6, 2);
  if (flags != 0) return "header flags are not 0";
  if (sx >= n || sy >= n) return "shift outside the tile";
  if (group >= groups) return "group without frequency tables";
  std::memcpy(&out->state, block + kEntropyBlockHeader, 4);
  if (out->state < kRansLow || out->state >= (kRansLow << 8)) return "rANS state out of range";
  out->sx = sx;
  out->sy = sy;
  out->group = group;
  return nullptr;
}

// Builds the decoder tables of `Contexts` contexts from one group's frequencies (256 per
// context): symbol lookup, frequency and cumulative start per context, and whether the context has
// a table. nullptr on success, else what is wrong.
template <int Contexts>
const char* build_rans_tables(const uint16_t* freq, uint8_t (*symbol)[kRansScale],
                              uint16_t (*frequency)[256], uint16_t (*start)[256],
                              bool* has_table) noexcept {
  for (int c = 0; c < Contexts; ++c) {
    uint32_t total = 0;
    for (int s = 0; s < 256; ++s) {
      const uint32_t f = freq[c * 256 + s];
      if (total + f > kRansScale) return "frequencies do not sum to 4096";
      frequency[c][s] = uint16_t(f);
      start[c][s] = uint16_t(total);
      if (f > 0) std::memset(symbol[c] + total, s, f);
      total += f;
    }
    if (total != 0 && total != kRansScale) return "frequencies do not sum to 4096";
    has_table[c] = total == kRansScale;
  }
  return nullptr;
}

// One rANS decoding step: the state x, whose low kRansScaleBits are `slot`, moves past the symbol
// of frequency `freq` starting at `start` (start <= slot < start + freq), then takes bytes of
// block[pos, size) until it is at least kRansLow again. False when the block runs out. The step of
// every rANS decoder of the reader (parallax versions 1 and 2, coded coefficients).
inline bool rans_advance(uint32_t freq, uint32_t start, uint32_t slot, const uint8_t* block,
                         uint64_t size, uint64_t& pos, uint32_t& x) noexcept {
  x = freq * (x >> kRansScaleBits) + slot - start;
  while (x < kRansLow) {
    if (pos >= size) return false;
    x = (x << 8) | block[pos++];
  }
  return true;
}

// Checks `Contexts` rows of 256 frequencies: each sums to 4096 or is all zero (an unused context).
// OK, or Malformed / CBK-E021 naming the context and its sum.
template <int Contexts>
Status check_rans_tables(const uint16_t* tables, const char* name) noexcept {
  for (int c = 0; c < Contexts; ++c) {
    uint32_t total = 0;
    for (int s = 0; s < 256; ++s)
      total += tables[c * 256 + s];
    if (total != 0 && total != kRansScale)
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "%s: the frequencies of context %d sum to %u, not 4096 (or 0)", name, c,
                           unsigned(total));
  }
  return {};
}

}  // namespace clothbake::reader::detail

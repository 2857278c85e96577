// Entropy-coded parallax blocks: the decoder (parallax_entropy.hpp).
#include "formats/reader/parallax_entropy.hpp"

#include <cstring>

namespace clothbake::reader {
namespace {

Status bad(const char* what) noexcept {
  return Status::error(ErrorCode::Malformed, Check::ValueRange,
                       "parallax_entropy: a block is not decodable: %s", what);
}

}  // namespace

Status check_parallax_tables(const uint16_t* group_tables) noexcept {
  for (int c = 0; c < kEntropyContexts; ++c) {
    uint32_t total = 0;
    for (int s = 0; s < 256; ++s)
      total += group_tables[c * 256 + s];
    if (total != 0 && total != kRansScale)
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "parallax_entropy: the frequencies of context %d sum to %u, not 4096 "
                           "(or 0)",
                           c, unsigned(total));
  }
  return {};
}

Status decode_parallax_block(const uint8_t* block, uint64_t size, const uint16_t* tables,
                             uint32_t groups, uint32_t n, uint8_t* plane,
                             ParallaxEntropyScratch* scratch) noexcept {
  const uint64_t count = uint64_t(n) * n;
  auto fail = [&](const char* what) {
    std::memset(plane, 0, count);
    return bad(what);
  };
  if (block == nullptr || tables == nullptr) return fail("no bytes");
  if (size < kEntropyBlockHeader + 4) return fail("shorter than its header");
  uint16_t sx16, sy16, group, flags;
  std::memcpy(&sx16, block, 2);
  std::memcpy(&sy16, block + 2, 2);
  std::memcpy(&group, block + 4, 2);
  std::memcpy(&flags, block + 6, 2);
  const uint32_t sx = sx16, sy = sy16;
  if (flags != 0) return fail("header flags are not 0");
  if (sx >= n || sy >= n) return fail("shift outside the tile");
  if (group >= groups) return fail("group without frequency tables");
  const uint16_t* freq = tables + uint64_t(group) * kEntropyContexts * 256;
  bool has_table[kEntropyContexts] = {};
  for (int c = 0; c < kEntropyContexts; ++c) {
    uint32_t total = 0;
    for (int s = 0; s < 256; ++s) {
      const uint32_t f = freq[c * 256 + s];
      if (total + f > kRansScale) return fail("frequencies do not sum to 4096");
      scratch->freq[c][s] = uint16_t(f);
      scratch->start[c][s] = uint16_t(total);
      if (f > 0) std::memset(scratch->symbol[c] + total, s, f);
      total += f;
    }
    if (total != 0 && total != kRansScale) return fail("frequencies do not sum to 4096");
    has_table[c] = total == kRansScale;
  }
  uint64_t pos = kEntropyBlockHeader;
  uint32_t x;
  std::memcpy(&x, block + pos, 4);
  pos += 4;
  if (x < kRansLow || x >= (kRansLow << 8)) return fail("rANS state out of range");
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t tx = 0; tx < n; ++tx) {
      const EntropyPrediction p = predict_parallax_code(plane, n, tx, y, sx, sy);
      if (!has_table[p.context]) return fail("a context is used without a frequency table");
      const uint32_t slot = x & (kRansScale - 1);
      const uint8_t sym = scratch->symbol[p.context][slot];
      x = uint32_t(scratch->freq[p.context][sym]) * (x >> kRansScaleBits) + slot -
          scratch->start[p.context][sym];
      while (x < kRansLow) {
        if (pos >= size) return fail("stream ends early");
        x = (x << 8) | block[pos++];
      }
      plane[uint64_t(y) * n + tx] = uint8_t(p.value + sym);
    }
  if (x != kRansLow) return fail("the coder does not end in its initial state");
  if (pos != size) return fail("bytes after the coded stream");
  return {};
}

}  // namespace clothbake::reader

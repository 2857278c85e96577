// Hierarchically predicted parallax blocks: the decoder (parallax_hierarchy.hpp).
#include "formats/reader/parallax_hierarchy.hpp"

#include <cstring>

namespace clothbake::reader {
namespace {

Status bad(const char* what) noexcept {
  return Status::error(ErrorCode::Malformed, Check::ValueRange,
                       "parallax_entropy: a hierarchical block is not decodable: %s", what);
}

}  // namespace

Status check_hierarchical_tables(const uint16_t* group_tables) noexcept {
  for (int c = 0; c < kHierContexts; ++c) {
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

Status decode_hierarchical_block(const uint8_t* block, uint64_t size, const uint16_t* tables,
                                 uint32_t groups, uint32_t n, uint32_t md,
                                 const uint16_t* const* refs, const uint32_t* ref_m, int k,
                                 uint16_t* plane, int32_t* diff,
                                 ParallaxHierScratch* scratch) noexcept {
  const uint64_t count = uint64_t(n) * n;
  auto fail = [&](const char* what) {
    std::memset(plane, 0, count * sizeof(uint16_t));
    return bad(what);
  };
  if (block == nullptr || tables == nullptr) return fail("no bytes");
  if (k < 0 || k > 4) return fail("more than four references");
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
  const uint16_t* freq = tables + uint64_t(group) * kHierContexts * 256;
  bool has_table[kHierContexts] = {};
  for (int c = 0; c < kHierContexts; ++c) {
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
  // One symbol of context `c`; false when the context has no table or the stream runs out.
  auto next = [&](int c, uint32_t* symbol) {
    if (!has_table[c]) return false;
    const uint32_t slot = x & (kRansScale - 1);
    const uint8_t s = scratch->symbol[c][slot];
    x = uint32_t(scratch->freq[c][s]) * (x >> kRansScaleBits) + slot - scratch->start[c][s];
    while (x < kRansLow) {
      if (pos >= size) return false;
      x = (x << 8) | block[pos++];
    }
    *symbol = s;
    return true;
  };
  uint32_t ref_codes[4];
  for (uint32_t ty = 0; ty < n; ++ty)
    for (uint32_t tx = 0; tx < n; ++tx) {
      const uint64_t t = uint64_t(ty) * n + tx;
      for (int e = 0; e < k; ++e)
        ref_codes[e] = refs[e][t];
      const ReferencePrediction ref = reference_prediction(ref_codes, ref_m, k, md);
      const EntropyPrediction p = predict_parallax_difference(diff, n, tx, ty, sx, sy, ref.spread);
      uint32_t s;
      if (!next(p.context, &s)) return fail("the stream ends early or a context has no table");
      int32_t residual;
      if (s != uint32_t(kHierEscape)) {
        residual = int32_t(s) - kHierDirectMax;
      } else {
        uint32_t high, low;
        if (!next(kHierEscapeHighContext, &high) || !next(kHierEscapeLowContext, &low))
          return fail("the stream ends early or an escape context has no table");
        residual = int32_t(int16_t(uint16_t((high << 8) | low)));
      }
      const uint16_t code = uint16_t(uint32_t(int64_t(ref.ref) + p.value + residual) & 0xFFFFu);
      plane[t] = code;
      diff[t] = int32_t(code) - int32_t(ref.ref);
    }
  if (x != kRansLow) return fail("the coder does not end in its initial state");
  if (pos != size) return fail("bytes after the coded stream");
  return {};
}

}  // namespace clothbake::reader

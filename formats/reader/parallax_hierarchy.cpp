// Hierarchically predicted parallax blocks: the decoder (parallax_hierarchy.hpp).
#include "formats/reader/parallax_hierarchy.hpp"

#include <cstring>

#include "formats/reader/detail/rans_block.hpp"

namespace clothbake::reader {
namespace {

Status undecodable_hierarchy(const char* what) noexcept {
  return Status::error(ErrorCode::Malformed, Check::ValueRange,
                       "parallax_entropy: a hierarchical block is not decodable: %s", what);
}

}  // namespace

Status check_hierarchical_tables(const uint16_t* group_tables) noexcept {
  return detail::check_rans_tables<kHierContexts>(group_tables, "parallax_entropy");
}

Status decode_hierarchical_block(const uint8_t* block, uint64_t size, const uint16_t* tables,
                                 uint32_t groups, uint32_t n, uint32_t md,
                                 const uint16_t* const* refs, const uint32_t* ref_m, int k,
                                 uint16_t* plane, int32_t* diff,
                                 ParallaxHierScratch* scratch) noexcept {
  const uint64_t count = uint64_t(n) * n;
  auto fail = [&](const char* what) {
    std::memset(plane, 0, count * sizeof(uint16_t));
    return undecodable_hierarchy(what);
  };
  if (block == nullptr || tables == nullptr) return fail("no bytes");
  if (k < 0 || k > 4) return fail("more than four references");
  detail::RansBlockStart start;
  if (const char* what = detail::read_rans_block_start(block, size, n, groups, &start))
    return fail(what);
  const uint32_t sx = start.sx, sy = start.sy;
  bool has_table[kHierContexts] = {};
  if (const char* what = detail::build_rans_tables<kHierContexts>(
          tables + uint64_t(start.group) * kHierContexts * 256, scratch->symbol, scratch->freq,
          scratch->start, has_table))
    return fail(what);
  uint64_t pos = kEntropyBlockHeader + 4;
  uint32_t x = start.state;
  // One symbol of context `c`; false when the context has no table or the stream runs out.
  auto next = [&](int c, uint32_t* symbol) {
    if (!has_table[c]) return false;
    const uint32_t slot = x & (kRansScale - 1);
    const uint8_t s = scratch->symbol[c][slot];
    *symbol = s;
    return detail::rans_advance(scratch->freq[c][s], scratch->start[c][s], slot, block, size, pos,
                                x);
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

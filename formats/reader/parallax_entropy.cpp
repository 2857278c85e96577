// Entropy-coded parallax blocks: the decoder (parallax_entropy.hpp).
#include "formats/reader/parallax_entropy.hpp"

#include <cstring>

#include "formats/reader/detail/rans_block.hpp"

namespace clothbake::reader {
namespace {

Status undecodable_block(const char* what) noexcept {
  return Status::error(ErrorCode::Malformed, Check::ValueRange,
                       "parallax_entropy: a block is not decodable: %s", what);
}

}  // namespace

Status check_parallax_tables(const uint16_t* group_tables) noexcept {
  return detail::check_rans_tables<kEntropyContexts>(group_tables, "parallax_entropy");
}

Status decode_parallax_block(const uint8_t* block, uint64_t size, const uint16_t* tables,
                             uint32_t groups, uint32_t n, uint8_t* plane,
                             ParallaxEntropyScratch* scratch) noexcept {
  const uint64_t count = uint64_t(n) * n;
  auto fail = [&](const char* what) {
    std::memset(plane, 0, count);
    return undecodable_block(what);
  };
  if (block == nullptr || tables == nullptr) return fail("no bytes");
  detail::RansBlockStart start;
  if (const char* what = detail::read_rans_block_start(block, size, n, groups, &start))
    return fail(what);
  const uint32_t sx = start.sx, sy = start.sy;
  bool has_table[kEntropyContexts] = {};
  if (const char* what = detail::build_rans_tables<kEntropyContexts>(
          tables + uint64_t(start.group) * kEntropyContexts * 256, scratch->symbol, scratch->freq,
          scratch->start, has_table))
    return fail(what);
  uint64_t pos = kEntropyBlockHeader + 4;
  uint32_t x = start.state;
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t tx = 0; tx < n; ++tx) {
      const EntropyPrediction p = predict_parallax_code(plane, n, tx, y, sx, sy);
      if (!has_table[p.context]) return fail("a context is used without a frequency table");
      const uint32_t slot = x & (kRansScale - 1);
      const uint8_t sym = scratch->symbol[p.context][slot];
      if (!detail::rans_advance(scratch->freq[p.context][sym], scratch->start[p.context][sym], slot,
                                block, size, pos, x))
        return fail("stream ends early");
      plane[uint64_t(y) * n + tx] = uint8_t(p.value + sym);
    }
  if (x != kRansLow) return fail("the coder does not end in its initial state");
  if (pos != size) return fail("bytes after the coded stream");
  return {};
}

}  // namespace clothbake::reader

// Entropy-coded C-PCA coefficients: the decoder (compressed_coefficients.hpp).
#include "formats/reader/compressed_coefficients.hpp"

#include <cstring>

#include "formats/reader/detail/rans_block.hpp"
#include "formats/reader/parallax_entropy.hpp"  // the rANS constants

namespace clothbake::reader {
namespace {

Status undecodable_coefficients(const char* what) noexcept {
  return Status::error(ErrorCode::Malformed, Check::ValueRange,
                       "compressed_tables: the coded coefficients are not decodable: %s", what);
}

}  // namespace

Status decode_compressed_coefficients(const uint8_t* stream, uint64_t size, uint32_t n,
                                      const uint8_t* map, const uint32_t* ranks,
                                      const uint32_t* first, uint64_t coefficient_count,
                                      int16_t* out) noexcept {
  auto fail = [&](const char* what) {
    if (coefficient_count > 0) std::memset(out, 0, coefficient_count * sizeof(int16_t));
    return undecodable_coefficients(what);
  };
  if (stream == nullptr) return fail("no bytes");
  if (size < kCoefficientHeaderBytes + kCoefficientTableBytes)
    return fail("shorter than its header and tables");
  uint32_t count, contexts, x;
  uint16_t sx, sy;
  std::memcpy(&count, stream, 4);
  std::memcpy(&sx, stream + 4, 2);
  std::memcpy(&sy, stream + 6, 2);
  std::memcpy(&contexts, stream + 8, 4);
  std::memcpy(&x, stream + 12, 4);
  if (count != coefficient_count) return fail("the count differs from the cells'");
  if (sx >= n || sy >= n) return fail("shift outside the tile");
  if (contexts != kCoefficientContexts) return fail("the number of contexts is not 32");
  if (x < kRansLow || x >= (kRansLow << 8)) return fail("rANS state out of range");
  uint16_t freq[kCoefficientContexts][kCoefficientSymbols];
  uint16_t start[kCoefficientContexts][kCoefficientSymbols];
  bool has_table[kCoefficientContexts] = {};
  std::memcpy(freq, stream + kCoefficientHeaderBytes, kCoefficientTableBytes);
  for (uint32_t c = 0; c < kCoefficientContexts; ++c) {
    uint32_t total = 0;
    for (uint32_t s = 0; s < kCoefficientSymbols; ++s) {
      start[c][s] = uint16_t(total);
      total += freq[c][s];
      if (total > kRansScale) return fail("frequencies do not sum to 4096");
    }
    if (total != 0 && total != kRansScale) return fail("frequencies do not sum to 4096");
    has_table[c] = total == kRansScale;
  }
  uint64_t pos = kCoefficientHeaderBytes + kCoefficientTableBytes;
  // A bit length in context c (a linear search of at most 32 symbols).
  auto bit_length = [&](uint32_t c, uint32_t* b) {
    if (!has_table[c]) return false;
    const uint32_t slot = x & (kRansScale - 1);
    uint32_t s = 0;  // the symbol whose range [start, start + freq) holds the slot
    while (s < kCoefficientSymbols &&
           !(freq[c][s] > 0 && slot < uint32_t(start[c][s]) + freq[c][s]))
      ++s;
    if (s == kCoefficientSymbols) return false;
    *b = s;
    return detail::rans_advance(freq[c][s], start[c][s], slot, stream, size, pos, x);
  };
  // k uniform bits (1 <= k <= 8).
  auto uniform_bits = [&](uint32_t k, uint32_t* v) {
    const uint32_t shift = kRansScaleBits - k, f = kRansScale >> k;
    const uint32_t slot = x & (kRansScale - 1);
    *v = slot >> shift;
    return detail::rans_advance(f, *v << shift, slot, stream, size, pos, x);
  };
  uint64_t next = 0;
  for (uint32_t ty = 0; ty < n; ++ty)
    for (uint32_t tx = 0; tx < n; ++tx) {
      const uint64_t t = uint64_t(ty) * n + tx;
      const uint8_t g = map[t];
      if (g == kNoCell) continue;
      for (uint32_t j = 0; j < ranks[g]; ++j) {
        const CoefficientPrediction p = predict_coefficient(out, first, map, n, tx, ty, j, sx, sy);
        uint32_t b;
        if (!bit_length(p.context, &b))
          return fail("the stream ends early or a context has no table");
        if (b > kCoefficientMaxBits) return fail("a bit length above 17");
        uint32_t z = b == 0 ? 0u : 1u;
        for (uint32_t left = b > 0 ? b - 1 : 0; left > 0;) {
          const uint32_t k = left < 8 ? left : 8;
          uint32_t v;
          if (!uniform_bits(k, &v)) return fail("the stream ends early");
          z = (z << k) | v;
          left -= k;
        }
        const int32_t r = (z & 1u) ? -int32_t((z + 1) >> 1) : int32_t(z >> 1);
        const int32_t q = p.value + r;
        if (q < -32767 || q > 32767) return fail("a coefficient outside [-32767, 32767]");
        out[next++] = int16_t(q);
      }
    }
  if (next != coefficient_count) return fail("the cells hold another number of coefficients");
  if (x != kRansLow) return fail("the coder does not end in its initial state");
  if (pos != size) return fail("bytes after the coded stream");
  return {};
}

}  // namespace clothbake::reader

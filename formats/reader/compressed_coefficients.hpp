// Entropy-coded C-PCA coefficients of the compressed Integral-Radiance tables (part 5,
// Coefficients, of radiance_compressed; layout in docs/format.md, "Coded coefficients"; why:
// docs/compression.md, "Coded coefficients").
//
// The coefficients (compressed_layout.hpp): for every texel in row-major
// order, the r_g quantised coefficients q_0 .. q_{r-1} of its cell g (none for a texel without a
// cell), each in [-32767, 32767]. They are coded losslessly in that order. Coefficient j of texel
// t = (x, y) is predicted from the same coefficient of neighbouring texels of the same cell:
//   - in the shift region of the stream's shift (sx, sy) != (0, 0) (y >= sy when sy > 0, else
//     x >= sx), when texel (x - sx mod N, y - sy) has the same cell: that texel's q_j (a tile that
//     repeats);
//   - else, when the texels above (x, y - 1), left (x - 1, y) and above-left (x - 1, y - 1) exist
//     (y > 0, x > 0) and all have the same cell: the median edge detector of left a, above b,
//     above-left c (min(a, b) if c >= max(a, b), max(a, b) if c <= min(a, b), else a + b - c);
//   - else the texel above if it exists and has the same cell, else the texel to the left if it
//     exists and has the same cell, else 0.
// No wrapping at the tile's borders. The context is 4 * min(j, 7) + m, m by the prediction P:
// 0 if P = 0, 1 if |P| < 32, 2 if |P| < 512, else 3. The residual R = q - P (in [-65534, 65534])
// is zigzag-mapped, z = 2R for R >= 0 and -2R - 1 otherwise, and coded as its bit length b
// (0 for z = 0; at most 17) with the context's frequency table, followed for b >= 2 by the b - 1
// bits of z below its leading one, most significant first, in chunks of at most 8 bits, each
// chunk k bits wide coded uniformly (frequency 4096 >> k, start = value << (12 - k)).
//
// Stream (u8, little-endian): u32 count, u16 sx, u16 sy, u32 contexts (= 32), u32 final rANS
// state x0 in [2^23, 2^31), u16 freq[32][32] (the bit-length symbols 0..31 of each context; each
// row sums to 4096 or is all zero), then the renormalisation bytes in reading order. The rANS
// coder is the block coder's (parallax_entropy.hpp): 12-bit frequencies,
// 32-bit state, byte renormalisation, the coder ending in its initial state 2^23 with every byte
// read.
//
// C++17, standard library only, no allocation, safe on hostile bytes: every read is bounded,
// every decoded value is range-checked, errors are Malformed / CBK-E021 naming what is wrong.
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/compressed_layout.hpp"
#include "formats/reader/status.hpp"

namespace clothbake::reader {

inline constexpr uint32_t kCoefficientContexts = 32;
inline constexpr uint32_t kCoefficientSymbols = 32;  // bit lengths 0..17 used
inline constexpr uint32_t kCoefficientMaxBits = 17;
inline constexpr uint32_t kCoefficientHeaderBytes = 16;
inline constexpr uint32_t kCoefficientTableBytes = kCoefficientContexts * kCoefficientSymbols * 2;

// The prediction of coefficient j of texel (x, y) and its context (file comment). `q` holds the
// decoded coefficients, `first` each texel's first coefficient index, `map` the cell map (n x n).
struct CoefficientPrediction {
  int32_t value;
  uint32_t context;
};
inline CoefficientPrediction predict_coefficient(const int16_t* q, const uint32_t* first,
                                                 const uint8_t* map, uint32_t n, uint32_t x,
                                                 uint32_t y, uint32_t j, uint32_t sx,
                                                 uint32_t sy) noexcept {
  const uint64_t t = uint64_t(y) * n + x;
  const uint8_t g = map[t];
  int32_t p = 0;
  const bool shifted = (sx | sy) != 0 && (sy > 0 ? y >= sy : x >= sx);
  const uint64_t ts = shifted ? uint64_t(y - sy) * n + (x >= sx ? x - sx : x + n - sx) : 0;
  if (shifted && map[ts] == g) {
    p = q[first[ts] + j];
  } else {
    const bool up = y > 0 && map[t - n] == g, left = x > 0 && map[t - 1] == g;
    if (up && left && map[t - n - 1] == g) {
      const int32_t a = q[first[t - 1] + j], b = q[first[t - n] + j], c = q[first[t - n - 1] + j];
      const int32_t hi = a > b ? a : b, lo = a > b ? b : a;
      p = c >= hi ? lo : (c <= lo ? hi : a + b - c);
    } else if (up) {
      p = q[first[t - n] + j];
    } else if (left) {
      p = q[first[t - 1] + j];
    }
  }
  const int32_t m = p < 0 ? -p : p;
  const uint32_t magnitude = p == 0 ? 0 : (m < 32 ? 1 : (m < 512 ? 2 : 3));
  return {p, 4 * (j < 7 ? j : 7) + magnitude};
}

// Decodes a stream of `size` bytes into `out` (coefficient_count values), given the cell map
// (n x n, already validated: every entry < cells or kNoCell), each cell's rank, each texel's first
// coefficient index (`first`, n x n, consistent with the map and ranks) and the expected count.
// Errors: Malformed / Check::ValueRange (CBK-E021): the header (count, shift, contexts, state), a
// frequency table, a context without a table, a bit length above 17, a coefficient outside
// [-32767, 32767], the stream running out, the final state or trailing bytes. Preconditions:
// 1 <= n <= 16384, out holds coefficient_count values.
Status decode_compressed_coefficients(const uint8_t* stream, uint64_t size, uint32_t n,
                                      const uint8_t* map, const uint32_t* ranks,
                                      const uint32_t* first, uint64_t coefficient_count,
                                      int16_t* out) noexcept;

}  // namespace clothbake::reader

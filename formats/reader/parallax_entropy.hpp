// The block coder (docs/format.md, "The block coder"; docs/compression.md says why): one N x N
// plane of byte symbols, coded in raster order (y, then x) as residuals modulo 256 against a
// causal prediction, with a static rANS coder (12-bit frequencies, 32-bit state, byte
// renormalisation) and one frequency table per context, shared by a group of blocks (the tables
// are stored once per group, outside the blocks). The feature maps (map_entropy.hpp) code each
// byte plane of their 16-bit codes as one block; the compressed parallax (parallax_hierarchy.hpp)
// uses the same block header, prediction rules, coder and renormalisation with its own contexts.
//   - a texel in the block's "shift region" (shift (sx, sy) != (0, 0): y >= sy when sy > 0, else
//     x >= sx) is predicted by the texel (x - sx mod N, y - sy), already decoded: context 4. Woven
//     tiles repeat (the twill's 256^2 tile is the same after a (64, 64) shift), so these
//     residuals are almost all 0;
//   - every other texel by the median edge detector of LOCO-I / JPEG-LS on its left a, upper b
//     and upper-left c neighbours (a = left if x > 0, else upper if y > 0, else 0; b = upper if
//     y > 0, else a; c = upper-left if x > 0 and y > 0, else a): pred = min(a, b) if c >= max(a,
//     b), max(a, b) if c <= min(a, b), a + b - c otherwise; context by g = |a - c| + |b - c|:
//     0 (g = 0), 1 (g < 3), 2 (g < 10), 3 (otherwise).
//
// Decoding is bounded and safe on hostile bytes: exactly N^2 symbols are produced per block, every
// read is checked against the block's length, frequency tables are validated (each context's
// frequencies sum to 4096 or are all zero), and a block whose coder does not end in its initial
// state with every byte consumed is reported (CBK-E021). C++17, standard library only, no
// allocation (the caller gives the output plane and a ParallaxEntropyScratch).
//
// Block (little-endian): u16 sx, u16 sy (the shift; both < N), u16 group (< G), u16 flags (0),
// u32 the coder's final state x (in [2^23, 2^31)), then the renormalisation bytes in reading order.
// Decoding texel i: slot = x mod 4096, the symbol s whose cumulative range [start_s, start_s + f_s)
// holds slot (context of the texel, the block's group), x = f_s (x >> 12) + slot - start_s, then
// while x < 2^23: x = (x << 8) | next byte; value = (prediction + s) mod 256. After the last texel
// x must be 2^23 and every byte consumed.
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/status.hpp"

namespace clothbake::reader {

inline constexpr uint32_t kEntropyParallaxInfoInstance = 0;     // CompressedParallaxInfoRecord
inline constexpr uint32_t kEntropyParallaxStepsInstance = 1;    // f64 {D}
inline constexpr uint32_t kEntropyParallaxOffsetsInstance = 2;  // u64 {D + 1}
inline constexpr uint32_t kEntropyParallaxStreamInstance = 3;   // u8 {bytes}
inline constexpr uint32_t kEntropyParallaxTablesInstance = 4;   // u16 {G, 23, 256}

inline constexpr int kEntropyContexts = 5;  // 4 MED gradient contexts + the shift context
inline constexpr int kEntropyShiftContext = 4;
inline constexpr uint32_t kRansScaleBits = 12;  // frequencies sum to 4096
inline constexpr uint32_t kRansScale = 1u << kRansScaleBits;
inline constexpr uint32_t kRansLow = 1u << 23;      // state interval [2^23, 2^31)
inline constexpr uint32_t kEntropyBlockHeader = 8;  // u16 sx, u16 sy, u16 group, u16 flags (0)
inline constexpr uint32_t kMaxEntropyGroups = 65536;
// CompressedParallaxInfoRecord::flags bit of a scene-planned table: the view directions that
// bin_map instance 1 leaves out have empty blocks (offsets[d] == offsets[d + 1]) and answer
// OutOfPlan.
inline constexpr uint32_t kEntropyPlannedFlag = 1;

// The causal prediction of texel (x, y) of a plane (row-major, n wide) from already decoded
// texels, and its context (see the file comment).
struct EntropyPrediction {
  int value;
  int context;
};
inline EntropyPrediction predict_parallax_code(const uint8_t* plane, uint32_t n, uint32_t x,
                                               uint32_t y, uint32_t sx, uint32_t sy) noexcept {
  const bool shifted = (sx | sy) != 0 && (sy > 0 ? y >= sy : x >= sx);
  if (shifted) {
    const uint32_t rx = x >= sx ? x - sx : x + n - sx;
    return {plane[uint64_t(y - sy) * n + rx], kEntropyShiftContext};
  }
  const uint64_t row = uint64_t(y) * n;
  const int a = x > 0 ? plane[row + x - 1] : (y > 0 ? plane[row - n + x] : 0);
  const int b = y > 0 ? plane[row - n + x] : a;
  const int c = (x > 0 && y > 0) ? plane[row - n + x - 1] : a;
  const int hi = a > b ? a : b, lo = a > b ? b : a;
  const int pred = c >= hi ? lo : (c <= lo ? hi : a + b - c);
  const int g = (a > c ? a - c : c - a) + (b > c ? b - c : c - b);
  return {pred, g == 0 ? 0 : (g < 3 ? 1 : (g < 10 ? 2 : 3))};
}

// Decoder tables of one block (about 21 KB; reusable across blocks).
struct ParallaxEntropyScratch {
  uint8_t symbol[kEntropyContexts][kRansScale];
  uint16_t freq[kEntropyContexts][256];
  uint16_t start[kEntropyContexts][256];
};

// Checks one group's tables (kEntropyContexts x 256 u16 frequencies): each context's row sums to
// 4096 or is all zero (a context the group does not use). Malformed / CBK-E021 otherwise.
Status check_parallax_tables(const uint16_t* group_tables) noexcept;

// Decodes one block (`size` bytes at `block`) into `plane` (n * n codes), with the frequency
// tables of `groups` groups at `tables` (u16 {groups, 5, 256}; the block names its group).
// Errors: Malformed with Check::ValueRange (CBK-E021) naming what is wrong (header, shift, group,
// a frequency table, a context used without a table, the stream running out, the final state or
// trailing bytes); `plane` is then zero-filled. Precondition: 1 <= n <= 16384, plane holds n * n
// bytes.
Status decode_parallax_block(const uint8_t* block, uint64_t size, const uint16_t* tables,
                             uint32_t groups, uint32_t n, uint8_t* plane,
                             ParallaxEntropyScratch* scratch) noexcept;

}  // namespace clothbake::reader

// Hierarchically predicted parallax codes (the compressed parallax, sections parallax_entropy
// 0x0203, payload version 1; layout in docs/format.md, "Compressed parallax"; docs/compression.md,
// "Hierarchical parallax", says why and what it measured).
//
// Codes. Direction d has its own step (tile-side units per code), chosen by the bake from the
// error target, and codes c_d(x, y) in [0, 65535]: r = -c_d * step[d]. Besides the f64 steps the
// section stores u32 weights m[d] in [1, 2^24], proportional to the steps (step[d] = unit * m[d]
// for one unit per table), with which directions predict each other in exact integer arithmetic.
//
// Levels and references. Bin (i, j) of the n x n direction grid (index j * n + i) is
//   level 0 when i % 4 == 0 and j % 4 == 0: no reference;
//   level 1 when i and j are even (and not level 0): references at distance 2, which are level 0:
//            (i +- 2, j +- 2) when i % 4 == 2 and j % 4 == 2, (i +- 2, j) when i % 4 == 2,
//            (i, j +- 2) otherwise;
//   level 2 otherwise: references at distance 1, which have even i and j (level 0 or 1):
//            (i +- 1, j +- 1) when i and j are odd, (i +- 1, j) when i is odd, (i, j +- 1)
//            otherwise;
// counting only references inside the grid (there is always at least one: i - 1, i - 2, j - 1,
// j - 2 are never negative where they are used). The references are listed in the order
// (i - a, j - b), (i + a, j - b), (i - a, j + b), (i + a, j + b) for diagonals and (-, +) for the
// two-sided cases, skipping those outside the grid. A reader decodes a level-2 plane after its
// references; no plane depends on more than one level below it.
//
// Prediction of texel t of direction d with references e_1 .. e_k (k = 0 for level 0):
//   S(t)   = sum_e c_e(t) m[e]                              (u64, exact)
//   ref(t) = floor((2 S + k m[d]) / (2 k m[d])), at most 65535  (k > 0; ref = 0 for k = 0)
//   spread bucket: the number of thresholds T in {1, 2, 4, 8} with
//            max_e c_e(t) m[e] - min_e c_e(t) m[e] >= T m[d]   (0 for k < 2)
//   D(t)   = c_d(t) - ref(t)                                (the difference plane, int32)
// D is predicted from its causal neighbours exactly as predict_parallax_code predicts byte codes
// (the shift copy, or the median edge detector on left a, upper b, upper-left c with the same
// border rules), giving a prediction P and a gradient bucket by g = |a - c| + |b - c|:
// 0 (g = 0), 1 (g < 3), 2 (g < 10), 3 (otherwise). The context is 4 * spread + gradient (0-19),
// or kHierShiftContext for a texel in the block's shift region. The residual R = D - P, taken
// modulo 65536 into [-32768, 32767], is coded as the symbol R + 127 when |R| <= 127, else as
// kHierEscape followed by two symbols, the high and the low byte of (R mod 65536), in the contexts
// kHierEscapeHighContext and kHierEscapeLowContext; each of the three is a full rANS decoding
// step. Decoding: c_d(t) = (ref + P + R) mod 65536.
//
// Blocks, groups, frequency tables and the rANS coder are those of the block coder
// (parallax_entropy.hpp: the same block header and renormalisation), with kHierContexts contexts
// per table. C++17, standard library only, no allocation, safe on hostile bytes: every read is
// bounded, all arithmetic is integer and cannot overflow for any stored values, a block that does
// not decode exactly reports CBK-E021 and leaves a zero plane.
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/status.hpp"

namespace clothbake::reader {

// Payload version of the compressed parallax (every instance of parallax_entropy).
inline constexpr uint16_t kHierParallaxVersion = 1;
// Instance 5: u32 {D} prediction weights m[d].
inline constexpr uint32_t kHierParallaxWeightsInstance = 5;
inline constexpr uint32_t kMaxHierWeight = 1u << 24;

inline constexpr int kHierSpreadBuckets = 5;
inline constexpr int kHierShiftContext = 20;
inline constexpr int kHierEscapeHighContext = 21;
inline constexpr int kHierEscapeLowContext = 22;
inline constexpr int kHierContexts = 23;
inline constexpr int kHierEscape = 255;     // the escape symbol (contexts 0-20)
inline constexpr int kHierDirectMax = 127;  // |R| <= 127: one symbol R + 127

// The references of bin (i, j) of an n x n grid and its level (file comment).
struct ParallaxReferences {
  int level = 0;
  int count = 0;
  uint32_t bin[4] = {0, 0, 0, 0};
};
inline ParallaxReferences parallax_references(uint32_t i, uint32_t j, uint32_t n) noexcept {
  ParallaxReferences r;
  const bool even = i % 2 == 0 && j % 2 == 0;
  if (even && i % 4 == 0 && j % 4 == 0) return r;  // level 0
  r.level = even ? 1 : 2;
  const int64_t a = even ? 2 : 1;
  int64_t dx[4], dy[4];
  int candidates = 0;
  const bool across_i = even ? i % 4 == 2 : i % 2 == 1;
  const bool across_j = even ? j % 4 == 2 : j % 2 == 1;
  if (across_i && across_j) {
    const int64_t ox[4] = {-a, a, -a, a}, oy[4] = {-a, -a, a, a};
    for (int k = 0; k < 4; ++k)
      dx[k] = ox[k], dy[k] = oy[k];
    candidates = 4;
  } else if (across_i) {
    dx[0] = -a, dy[0] = 0, dx[1] = a, dy[1] = 0;
    candidates = 2;
  } else {
    dx[0] = 0, dy[0] = -a, dx[1] = 0, dy[1] = a;
    candidates = 2;
  }
  for (int k = 0; k < candidates; ++k) {
    const int64_t x = int64_t(i) + dx[k], y = int64_t(j) + dy[k];
    if (x < 0 || y < 0 || x >= int64_t(n) || y >= int64_t(n)) continue;
    r.bin[r.count++] = uint32_t(y) * n + uint32_t(x);
  }
  return r;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // the bake's, not shading's (the single file leaves it out)
// Marks in `mask` (n * n entries, non-zero = kept, bin (i, j) at j * n + i) every direction that
// a kept one references, directly or through another: the directions a scene-planned hierarchical
// table must store (level 2 first, then level 1, so that references of added level-1 bins are
// added too).
inline void close_under_parallax_references(uint8_t* mask, uint32_t n) noexcept {
  for (int level = 2; level >= 1; --level)
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) {
        if (mask[uint64_t(j) * n + i] == 0) continue;
        const ParallaxReferences r = parallax_references(i, j, n);
        if (r.level != level) continue;
        for (int e = 0; e < r.count; ++e)
          mask[r.bin[e]] = 1;
      }
}
#endif

// The reference prediction of one texel from k reference codes `c` with weights `m` for a
// direction of weight `md` (file comment): ref(t), and the spread bucket.
struct ReferencePrediction {
  uint32_t ref;
  int spread;
};
inline ReferencePrediction reference_prediction(const uint32_t* c, const uint32_t* m, int k,
                                                uint32_t md) noexcept {
  if (k <= 0) return {0, 0};
  uint64_t sum = 0, lo = ~uint64_t(0), hi = 0;
  for (int e = 0; e < k; ++e) {
    const uint64_t v = uint64_t(c[e]) * m[e];
    sum += v;
    lo = v < lo ? v : lo;
    hi = v > hi ? v : hi;
  }
  const uint64_t den = 2 * uint64_t(k) * md;
  uint64_t ref = (2 * sum + uint64_t(k) * md) / den;
  if (ref > 65535) ref = 65535;
  int spread = 0;
  if (k >= 2) {
    const uint64_t s = hi - lo;
    spread = (s >= uint64_t(md)) + (s >= 2 * uint64_t(md)) + (s >= 4 * uint64_t(md)) +
             (s >= 8 * uint64_t(md));
  }
  return {uint32_t(ref), spread};
}

// The prediction P of the difference plane at (x, y) from its decoded causal part (row-major, n
// wide) and the texel's context, for a block with shift (sx, sy) and spread bucket `spread`.
inline EntropyPrediction predict_parallax_difference(const int32_t* diff, uint32_t n, uint32_t x,
                                                     uint32_t y, uint32_t sx, uint32_t sy,
                                                     int spread) noexcept {
  const bool shifted = (sx | sy) != 0 && (sy > 0 ? y >= sy : x >= sx);
  if (shifted) {
    const uint32_t rx = x >= sx ? x - sx : x + n - sx;
    return {diff[uint64_t(y - sy) * n + rx], kHierShiftContext};
  }
  const uint64_t row = uint64_t(y) * n;
  const int32_t a = x > 0 ? diff[row + x - 1] : (y > 0 ? diff[row - n + x] : 0);
  const int32_t b = y > 0 ? diff[row - n + x] : a;
  const int32_t c = (x > 0 && y > 0) ? diff[row - n + x - 1] : a;
  const int32_t hi = a > b ? a : b, lo = a > b ? b : a;
  const int32_t pred = c >= hi ? lo : (c <= lo ? hi : a + b - c);
  const int64_t g =
      (a > c ? int64_t(a) - c : int64_t(c) - a) + (b > c ? int64_t(b) - c : int64_t(c) - b);
  const int gradient = g == 0 ? 0 : (g < 3 ? 1 : (g < 10 ? 2 : 3));
  return {pred, 4 * spread + gradient};
}

// Decoder tables of one hierarchical block (about 100 KB; reusable across blocks).
struct ParallaxHierScratch {
  uint8_t symbol[kHierContexts][kRansScale];
  uint16_t freq[kHierContexts][256];
  uint16_t start[kHierContexts][256];
};

// Checks one group's tables (kHierContexts x 256 u16 frequencies): each context's row sums to
// 4096 or is all zero. Malformed / CBK-E021 otherwise.
Status check_hierarchical_tables(const uint16_t* group_tables) noexcept;

// Decodes one block (`size` bytes at `block`) of direction with weight `md` into `plane` (n * n
// codes), given its k (0..4) decoded reference planes `refs` with weights `ref_m`, the frequency
// tables of `groups` groups at `tables` (u16 {groups, kHierContexts, 256}), and `diff`, n * n
// int32 of scratch. Errors: Malformed / Check::ValueRange (CBK-E021) naming what is wrong; `plane`
// is then zero-filled. Preconditions: 1 <= n <= 16384; refs[0..k) hold n * n codes each; md and
// ref_m in [1, kMaxHierWeight].
Status decode_hierarchical_block(const uint8_t* block, uint64_t size, const uint16_t* tables,
                                 uint32_t groups, uint32_t n, uint32_t md,
                                 const uint16_t* const* refs, const uint32_t* ref_m, int k,
                                 uint16_t* plane, int32_t* diff,
                                 ParallaxHierScratch* scratch) noexcept;

}  // namespace clothbake::reader

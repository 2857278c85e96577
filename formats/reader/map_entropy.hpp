// Entropy-coded feature maps (the one form of height, tangent, normal, gap and albedo; docs/
// format.md, "Feature maps"): the 16-bit codes of map_encoding.hpp (the raw bit patterns: f16
// bits, two's-complement snorm16, unorm16), split into byte planes, each plane coded as one block
// of the block coder (parallax_entropy.hpp: LOCO-I prediction or the tile's repeat shift, static
// rANS, 5 contexts). Lossless: decoding gives exactly the codes, which map_encoding.hpp then turns
// into floats.
//
// Payload: u8 {bytes}, little-endian:
//   0   u32 resolution N (1..16384)
//   4   u32 planes P = 2 C (C = 16-bit codes per texel: height 1, tangent 2, normal 2, gap 1,
//       albedo 3); plane 2c holds the low bytes of channel c, plane 2c + 1 the high bytes, each
//       N x N in raster order (texel y N + x)
//   8   u32 groups G, 1..P: frequency-table sets
//   12  u32 reserved, 0
//   16  u64 offsets[P + 1]: plane p's block is bytes [offsets[p], offsets[p + 1]) of the block
//       area; offsets[0] = 0, non-decreasing
//   16 + 8 (P + 1)          u16 tables[G][5][256] (each context sums to 4096 or is all zero)
//   16 + 8 (P + 1) + 2560 G the block area, offsets[P] bytes, to the end of the payload
//
// C++17, standard library only, noexcept, no allocation (the caller gives the output and the
// scratch); safe on hostile bytes: every count, offset and table is checked before use, and each
// block is decoded by decode_parallax_block's bounded decoder.
#pragma once

#include <cstdint>

#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/status.hpp"

namespace clothbake::reader {

inline constexpr uint16_t kFeatureMapVersion = 1;  // payload version of the five coded maps
inline constexpr uint32_t kMapEntropyHeaderBytes = 16;
inline constexpr uint32_t kMapEntropyTableBytes = kEntropyContexts * 256 * 2;  // per group
inline constexpr uint32_t kMaxMapEntropyResolution = 16384;

// The header's counts, checked against the payload size: N, P and G as stored.
struct MapEntropyHeader {
  uint32_t resolution = 0;
  uint32_t planes = 0;
  uint32_t groups = 0;
};

// Parses and checks the header, the offsets and the tables of a payload of `size` bytes that
// should hold `channels` 16-bit codes per texel. Errors: Malformed with Check::ValueRange
// (CBK-E021) naming `what` (the map) and the fault; Check::SectionLayout (CBK-E015) if P is not
// 2 channels.
Status check_map_entropy(const char* what, const uint8_t* payload, uint64_t size, uint32_t channels,
                         MapEntropyHeader* out) noexcept;

// Decodes a payload that check_map_entropy accepted into codes[t * channels + c] (N^2 x channels
// 16-bit codes, host order), using `plane` (N^2 bytes) as the work buffer for one byte plane.
// Errors: Malformed with Check::ValueRange (CBK-E021) naming the map, the plane and the fault;
// `codes` is then zero-filled.
Status decode_map_entropy(const char* what, const uint8_t* payload, uint64_t size,
                          const MapEntropyHeader& header, uint16_t* codes, uint8_t* plane,
                          ParallaxEntropyScratch* scratch) noexcept;

}  // namespace clothbake::reader

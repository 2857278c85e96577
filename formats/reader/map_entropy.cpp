// Entropy-coded feature maps: header checks and decoding (map_entropy.hpp).
#include "formats/reader/map_entropy.hpp"

#include <cstring>

namespace clothbake::reader {
namespace {

uint32_t load32(const uint8_t* p) noexcept {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
uint64_t load64(const uint8_t* p) noexcept {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

uint64_t tables_offset(uint32_t planes) noexcept {
  return kMapEntropyHeaderBytes + 8ull * (planes + 1ull);
}

}  // namespace

Status check_map_entropy(const char* what, const uint8_t* payload, uint64_t size, uint32_t channels,
                         MapEntropyHeader* out) noexcept {
  auto bad = [what](const char* fault) {
    return Status::error(ErrorCode::Malformed, Check::ValueRange, "%s map (entropy-coded): %s",
                         what, fault);
  };
  if (payload == nullptr || size < kMapEntropyHeaderBytes) return bad("shorter than its header");
  MapEntropyHeader h;
  h.resolution = load32(payload);
  h.planes = load32(payload + 4);
  h.groups = load32(payload + 8);
  if (load32(payload + 12) != 0) return bad("reserved header bytes are not 0");
  if (h.planes != 2 * channels)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "%s map (entropy-coded) has %u byte planes, expected "
                         "%u",
                         what, unsigned(h.planes), unsigned(2 * channels));
  if (h.resolution == 0 || h.resolution > kMaxMapEntropyResolution)
    return bad("resolution outside 1..16384");
  if (h.groups == 0 || h.groups > h.planes) return bad("group count outside 1..planes");
  const uint64_t blocks = tables_offset(h.planes) + uint64_t(h.groups) * kMapEntropyTableBytes;
  if (size < blocks) return bad("shorter than its offsets and frequency tables");
  uint64_t previous = 0;
  for (uint32_t p = 0; p <= h.planes; ++p) {
    const uint64_t o = load64(payload + kMapEntropyHeaderBytes + 8ull * p);
    if ((p == 0 && o != 0) || o < previous) return bad("block offsets are not ascending from 0");
    previous = o;
  }
  if (previous != size - blocks) return bad("the last block offset is not the block area's size");
  // Tables: u16 values at an even offset of a 64-aligned payload; read bytewise all the same.
  for (uint32_t g = 0; g < h.groups; ++g) {
    uint16_t table[kEntropyContexts * 256];
    std::memcpy(table, payload + tables_offset(h.planes) + uint64_t(g) * kMapEntropyTableBytes,
                sizeof table);
    const Status s = check_parallax_tables(table);
    if (!s.ok()) return bad("a frequency table does not sum to 4096 (or 0)");
  }
  *out = h;
  return {};
}

Status decode_map_entropy(const char* what, const uint8_t* payload, uint64_t size,
                          const MapEntropyHeader& header, uint16_t* codes, uint8_t* plane,
                          ParallaxEntropyScratch* scratch) noexcept {
  const uint32_t n = header.resolution, channels = header.planes / 2;
  const uint64_t texels = uint64_t(n) * n;
  const uint8_t* tables_bytes = payload + tables_offset(header.planes);
  const uint64_t blocks =
      tables_offset(header.planes) + uint64_t(header.groups) * kMapEntropyTableBytes;
  // decode_parallax_block reads the tables as u16: the payload is 64-aligned and the table offset
  // even, so they are aligned.
  const uint16_t* tables = reinterpret_cast<const uint16_t*>(tables_bytes);
  for (uint64_t c = 0; c < channels * texels; ++c)
    codes[c] = 0;
  for (uint32_t p = 0; p < header.planes; ++p) {
    const uint64_t begin = load64(payload + kMapEntropyHeaderBytes + 8ull * p);
    const uint64_t end = load64(payload + kMapEntropyHeaderBytes + 8ull * (p + 1));
    if (end > size - blocks || begin > end)  // check_map_entropy's invariant, kept local
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "%s map (entropy-coded): plane %u lies outside the payload", what,
                           unsigned(p));
    const Status s = decode_parallax_block(payload + blocks + begin, end - begin, tables,
                                           header.groups, n, plane, scratch);
    if (!s.ok()) {
      for (uint64_t c = 0; c < channels * texels; ++c)
        codes[c] = 0;
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "%s map (entropy-coded): plane %u: %s", what, unsigned(p), s.message());
    }
    const uint32_t c = p / 2, shift = (p % 2) * 8;
    for (uint64_t t = 0; t < texels; ++t)
      codes[t * channels + c] = uint16_t(codes[t * channels + c] | (uint16_t(plane[t]) << shift));
  }
  return {};
}

}  // namespace clothbake::reader

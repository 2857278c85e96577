// Entropy-coded feature maps: the encoder (map_entropy.hpp).
#include "compress/map_entropy.hpp"

#include <cmath>
#include <cstring>

#include "common/error.hpp"
#include "compress/parallax_entropy.hpp"
#include "formats/reader/map_encoding.hpp"
#include "formats/reader/map_entropy.hpp"

namespace clothbake::compress {
namespace {

void put(std::vector<std::byte>& out, const void* p, std::size_t n) {
  const auto* b = static_cast<const std::byte*>(p);
  out.insert(out.end(), b, b + n);
}

}  // namespace

formats::Section entropy_code_map(const formats::Section& packed, const ShiftList* shifts,
                                  ShiftList* found) {
  const uint32_t type = uint32_t(packed.type);
  if (packed.version != reader::kFeatureMapPackedVersion || type < 0x0100 || type > 0x0105 ||
      type == 0x0104 || packed.dims.size() < 2 || packed.dims[0] != packed.dims[1] ||
      reader::element_size(packed.element) != 2)
    throw_internal_error("entropy_code_map: not a payload-version-2 feature map section");
  const uint32_t n = packed.dims[0];
  const uint32_t channels = packed.dims.size() == 3 ? packed.dims[2] : 1;
  const uint64_t texels = uint64_t(n) * n;
  const auto bytes = packed.bytes();
  if (bytes.size() != texels * channels * 2)
    throw_internal_error("entropy_code_map: payload size does not match the shape");
  const uint32_t planes = 2 * channels;
  std::vector<uint8_t> plane(texels);
  std::vector<std::vector<uint8_t>> blocks(planes);
  std::vector<uint16_t> tables;
  ShiftList candidates;
  for (uint32_t p = 0; p < planes; ++p) {
    const uint32_t c = p / 2, byte = p % 2;
    for (uint64_t t = 0; t < texels; ++t)
      plane[t] = std::to_integer<uint8_t>(bytes[(t * channels + c) * 2 + byte]);  // little-endian
    uint32_t best_sx = 0, best_sy = 0;
    std::vector<uint64_t> best = parallax_residual_counts(plane.data(), n, 0, 0);
    double best_bits = residual_entropy_bits(best);
    if (p == 0) {
      candidates = shifts ? *shifts : parallax_shift_candidates(plane.data(), n);
      if (found) *found = candidates;
    }
    for (const auto& [sx, sy] : candidates) {
      std::vector<uint64_t> counts = parallax_residual_counts(plane.data(), n, sx, sy);
      const double bits = residual_entropy_bits(counts);
      if (bits < best_bits) {
        best_bits = bits;
        best = std::move(counts);
        best_sx = sx;
        best_sy = sy;
      }
    }
    const std::vector<uint16_t> freq = parallax_frequencies(best);
    blocks[p] = encode_parallax_block(plane.data(), n, best_sx, best_sy, p, freq.data());
    tables.insert(tables.end(), freq.begin(), freq.end());
  }
  std::vector<std::byte> out;
  const uint32_t header[4] = {n, planes, planes, 0};
  put(out, header, sizeof header);
  uint64_t offset = 0;
  put(out, &offset, 8);
  for (const auto& b : blocks) {
    offset += b.size();
    put(out, &offset, 8);
  }
  put(out, tables.data(), tables.size() * sizeof(uint16_t));
  for (const auto& b : blocks)
    put(out, b.data(), b.size());
  if (out.size() >= bytes.size()) return packed;
  formats::Section s;
  s.type = packed.type;
  s.instance = packed.instance;
  s.version = reader::kFeatureMapEntropyVersion;
  s.element = reader::ElementType::U8;
  s.dims = {uint32_t(out.size())};
  s.payload = std::move(out);
  return s;
}

}  // namespace clothbake::compress

// Entropy-coded feature maps: the encoder (map_entropy.hpp).
#include "compress/map_entropy.hpp"

#include <cmath>
#include <cstring>

#include "common/error.hpp"
#include "compress/parallax_entropy.hpp"
#include "fabric/fabric_sections.hpp"
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
  if (type < 0x0100 || type > 0x0105 || type == 0x0104 || packed.dims.size() < 2 ||
      packed.dims[0] != packed.dims[1] || reader::element_size(packed.element) != 2)
    throw_internal_error("entropy_code_map: not a feature-map code array");
  const uint32_t n = packed.dims[0];
  const uint32_t channels = packed.dims.size() == 3 ? packed.dims[2] : 1;
  const uint64_t texels = uint64_t(n) * n;
  const auto bytes = packed.bytes();
  if (bytes.size() != texels * channels * 2)
    throw_internal_error("entropy_code_map: payload size does not match the shape");
  const uint32_t planes = 2 * channels;
  // Each plane's bytes, its shift (the smallest estimate of no shift and the candidates) and the
  // residual counts under it.
  std::vector<std::vector<uint8_t>> plane(planes, std::vector<uint8_t>(texels));
  std::vector<ShiftChoice> choice(planes);
  ShiftList candidates;
  for (uint32_t p = 0; p < planes; ++p) {
    const uint32_t c = p / 2, byte = p % 2;
    for (uint64_t t = 0; t < texels; ++t)  // little-endian codes: plane 2c low, 2c + 1 high bytes
      plane[p][t] = std::to_integer<uint8_t>(bytes[(t * channels + c) * 2 + byte]);
    if (p == 0) {
      candidates = shifts ? *shifts : parallax_shift_candidates(plane[0].data(), n);
      if (found) *found = candidates;
    }
    choice[p] = choose_shift(candidates, [&](uint32_t sx, uint32_t sy) {
      return parallax_residual_counts(plane[p].data(), n, sx, sy);
    });
  }
  // Two groupings of the frequency tables: one set per plane (large tiles: each plane's own
  // statistics), or one for all planes (small tiles, where 2.5 KB of tables per plane would
  // outweigh the blocks). Chosen by the Shannon estimate (residual bits plus tables) and coded
  // once: the pooled counts' entropy is exactly the cost of every plane under the shared tables.
  std::vector<uint64_t> pooled(choice[0].counts.size(), 0);
  double separate_bits = 0;
  for (const ShiftChoice& ch : choice) {
    separate_bits += residual_entropy_bits(ch.counts);
    for (std::size_t k = 0; k < pooled.size(); ++k)
      pooled[k] += ch.counts[k];
  }
  const double table_bits = 8.0 * reader::kMapEntropyTableBytes;
  const bool shared =
      residual_entropy_bits(pooled) + table_bits < separate_bits + planes * table_bits;
  const uint32_t groups = shared ? 1 : planes;
  std::vector<uint16_t> tables;
  if (shared) {
    tables = parallax_frequencies(pooled);
  } else {
    for (const ShiftChoice& ch : choice) {
      const std::vector<uint16_t> f = parallax_frequencies(ch.counts);
      tables.insert(tables.end(), f.begin(), f.end());
    }
  }
  const std::size_t table_size = tables.size() / groups;
  std::vector<std::vector<uint8_t>> blocks(planes);
  for (uint32_t p = 0; p < planes; ++p) {
    const uint32_t g = shared ? 0 : p;
    blocks[p] = encode_parallax_block(plane[p].data(), n, choice[p].sx, choice[p].sy, g,
                                      tables.data() + g * table_size);
  }
  std::vector<std::byte> out;
  const uint32_t header[4] = {n, planes, groups, 0};
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
  formats::Section s;
  s.type = packed.type;
  s.instance = packed.instance;
  s.version = reader::kFeatureMapVersion;
  s.element = reader::ElementType::U8;
  s.dims = {uint32_t(out.size())};
  s.payload = std::move(out);
  return s;
}

std::vector<formats::Section> feature_map_sections(const FabricMaps& maps) {
  std::vector<formats::Section> sections = feature_map_codes(maps);
  // The tile's repeat shifts are searched once, on the height map (the first section), and
  // tried on every map's byte planes.
  ShiftList shifts;
  bool searched = false;
  for (formats::Section& s : sections)
    if (s.type != reader::SectionType::YarnIdMap) {
      s = entropy_code_map(s, searched ? &shifts : nullptr, searched ? nullptr : &shifts);
      searched = true;
    }
  return sections;
}

}  // namespace clothbake::compress

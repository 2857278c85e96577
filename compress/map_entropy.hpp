// Encoder of the entropy-coded feature maps (format 1.4, payload version 3; the layout and the
// decoder: formats/reader/map_entropy.hpp; why: docs/format.md §6.4).
//
// Input: a feature map section of payload version 2 (16-bit codes: f16 height, octahedral i16
// tangent and normal, unorm16 gap and albedo; fabric/fabric_sections.hpp). Each byte plane (low
// and high byte of each code channel) is coded as one block of the parallax entropy coder
// (compress/parallax_entropy.hpp) with its own frequency tables: the block's shift is the best of
// no shift and the plane's repeat candidates by the entropy of its residuals. Lossless and
// deterministic. C++20.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress {

// The payload-version-3 form of `packed` (a version-2 map section), or `packed` itself when
// coding would not make it smaller (noisy maps, tiny tiles). Throws Error(Internal) for a section
// that is not a version-2 feature map.
// `shifts`: the tile's repeat candidates to try for every plane (parallax_shift_candidates); when
// null they are searched on the map's first byte plane (an O(N^2) search of 64^2 samples per
// shift, about 0.3 s at 256^2: the bake searches once, on the height map, and passes them on).
// `found` (optional) receives the candidates used.
using ShiftList = std::vector<std::pair<uint32_t, uint32_t>>;
formats::Section entropy_code_map(const formats::Section& packed, const ShiftList* shifts = nullptr,
                                  ShiftList* found = nullptr);

}  // namespace clothbake::compress

// Encoder of the entropy-coded feature maps, the one stored form of height, tangent, normal, gap
// and albedo (the layout and the decoder: formats/reader/map_entropy.hpp; docs/format.md,
// "Feature maps").
//
// Input: the 16-bit code arrays of fabric/fabric_sections.hpp (feature_map_codes: f16 height,
// octahedral i16 tangent and normal, unorm16 gap and albedo). Each byte plane (low and high byte
// of each code channel) is coded as one block of the block coder (compress/parallax_entropy.hpp):
// the block's shift is the best of no shift and the plane's repeat candidates by the entropy of
// its residuals; the frequency tables are one set per plane or one set for all planes, whichever
// the Shannon estimate says codes smaller (small tiles share). Lossless and deterministic. C++20.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "fabric/fabric.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress {

// The coded section of `codes` (one code array of feature_map_codes other than yarn_id), also
// where it is not smaller than the array (a noisy map costs its tables, 2.5 KB per set).
// Throws Error(Internal) for a section that is not such an array.
// `shifts`: the tile's repeat candidates to try for every plane (parallax_shift_candidates); when
// null they are searched on the map's first byte plane (an O(N^2) search of 64^2 samples per
// shift, about 0.3 s at 256^2: feature_map_sections searches once, on the height map, and passes
// them on). `found` (optional) receives the candidates used.
using ShiftList = std::vector<std::pair<uint32_t, uint32_t>>;
formats::Section entropy_code_map(const formats::Section& codes, const ShiftList* shifts = nullptr,
                                  ShiftList* found = nullptr);

// The six feature-map sections of `maps` as an asset stores them: the five coded maps and
// yarn_id. Throws what feature_map_codes throws (Error(Input) naming the map and texel).
std::vector<formats::Section> feature_map_sections(const FabricMaps& maps);

}  // namespace clothbake::compress

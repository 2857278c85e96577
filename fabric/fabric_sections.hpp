// Encoding of a Fabric into the fabric sections (FabricInfo, YarnMaterials and the six
// feature maps; payloads in docs/format.md and formats/reader/layout.hpp).
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "fabric/fabric.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake {

// FabricInfo and YarnMaterials. Yarn names longer than 31 bytes are cut at a UTF-8 character
// boundary (the full name is kept in the metadata). Throws Error(Input) for NaN/Inf parameters
// and for more than 65536 yarns (yarn ids are u16).
std::vector<formats::Section> fabric_record_sections(const Fabric& fabric);

// The six feature maps of `maps` (N x N) as they are before entropy coding: height f16
// {N, N}, tangent and normal i16 {N, N, 2} octahedral snorm16, gap u16 {N, N} and albedo
// u16 {N, N, 3} unorm16 (formats/writer/map_encoding.hpp gives the error bounds), and yarn_id
// u16 {N, N}, in that section order (height, tangent, normal, gap, yarn_id, albedo). yarn_id is
// its final section; the five code arrays are not an on-disk form: compress::feature_map_sections
// entropy-codes them (docs/format.md, "Feature maps"). Throws Error(Input) naming the map when a
// map does not have N*N texels or holds NaN/Inf (with the texel's x, y), or a height beyond the
// f16 range (|h| > 65504 tile sides); Error(Input) if N is not positive.
std::vector<formats::Section> feature_map_codes(const FabricMaps& maps);

// Provenance and parameters for the metadata section: fabric name, bake settings, yarn names,
// sheen, and every input file with its content hash (Fabric::inputs). Deterministic.
nlohmann::json fabric_metadata(const Fabric& fabric);

}  // namespace clothbake

// Encoding of a Fabric into the format-1 fabric sections (FabricInfo, YarnMaterials and the six
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

// How the feature maps are stored: Packed (the default; format 1.4, payload version 2 of height,
// tangent, normal, gap and albedo: f16, octahedral snorm16, unorm16; formats/writer/
// map_encoding.hpp gives the error bounds) or Float32 (payload version 1, f32 as in formats
// 1.0-1.3: for tests of old-asset compatibility and for readers that predate 1.4).
enum class MapEncoding { Packed, Float32 };

// The six feature maps of `maps` (N x N). Throws Error(Input) naming the map when a map does not
// have N*N texels or holds NaN/Inf (with the texel's x, y), or (Packed) a height beyond the f16
// range (|h| > 65504 tile sides); Error(Input) if N is not positive. yarn_id is u16 either way.
std::vector<formats::Section> feature_map_sections(const FabricMaps& maps,
                                                   MapEncoding encoding = MapEncoding::Packed);

// Provenance and parameters for the metadata section: fabric name, bake settings, yarn names,
// sheen, and every input file with its content hash (Fabric::inputs). Deterministic.
nlohmann::json fabric_metadata(const Fabric& fabric);

}  // namespace clothbake

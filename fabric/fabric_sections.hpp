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

// The six feature maps of `maps` (N x N). Throws Error(Input) naming the map when a map does not
// have N*N texels or holds NaN/Inf (with the texel's x, y); Error(Input) if N is not positive.
std::vector<formats::Section> feature_map_sections(const FabricMaps& maps);

// Provenance and parameters for the metadata section: fabric name, bake settings, yarn names,
// sheen, and every input file with its content hash (Fabric::inputs). Deterministic.
nlohmann::json fabric_metadata(const Fabric& fabric);

}  // namespace clothbake

// The asset metadata as JSON for the C++20 tools: the reader's limits (size, nesting), the JSON
// syntax, and the types of the keys docs/format.md §6.1 defines. One place, so that every command
// treats a bad metadata value the same way: as an invalid asset (exit 3), never an internal error.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "formats/reader/asset.hpp"

namespace clothbake::formats {

struct MetadataFinding {
  reader::Check check = reader::Check::None;  // Metadata (CBK-E020) or MetadataSchema (E023)
  std::string message;                        // "metadata: ..." naming the key
};

// Parses the asset's metadata section into `*out` (left null when it does not parse) and returns
// every finding: CBK-E019 when the section is absent; CBK-E020 over the size or nesting limits
// (reader::check_metadata_limits, checked before parsing), not JSON, not an object, or "format" is
// not "clothbake-asset"; CBK-E023 for each known key of the wrong JSON type (`tool` not an object
// of strings, `stages` not an array of strings, `fabric.inputs` entries not objects of strings,
// ...). Unknown keys are ignored (docs/format.md: readers ignore what they do not know).
std::vector<MetadataFinding> check_metadata(const reader::Asset& asset, nlohmann::json* out);

// The same checks on metadata text (everything but the CBK-E019 presence check): the limits, the
// JSON syntax, "format" and the schema. Used by check_metadata and the metadata fuzzer.
std::vector<MetadataFinding> check_metadata_text(std::string_view text, nlohmann::json* out);

// The metadata object, or throws clothbake::Error(InvalidAsset) with "CBK-E0nn: metadata: ..."
// for the first finding of check_metadata().
nlohmann::json read_metadata(const reader::Asset& asset);

}  // namespace clothbake::formats

// Opening an asset for a command that answers from it (query, export, eval, verify): through
// every check `clothbake validate` runs, so that no command answers from an asset validate
// rejects (docs/format.md, "Validation checks").
#pragma once

#include <string>

#include "formats/reader/asset.hpp"

namespace clothbake::formats {

// Opens `path` (structure), then runs reader::validate_asset (the header and every section
// checksum, then the rest) and the metadata checks (check_metadata). Throws clothbake::Error: Input (2) when the file cannot be
// read, InvalidAsset (3) with "CBK-E0nn: MESSAGE (N errors; clothbake validate lists them)" for
// the first error found. Warnings are allowed. Cost: one pass over the asset plus opening every
// baked view (what validate costs).
reader::Asset open_valid_asset(const std::string& path);

}  // namespace clothbake::formats

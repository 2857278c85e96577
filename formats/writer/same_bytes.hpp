// Restat support: does a file already hold exactly the bytes that writing an asset would produce?
// A bake whose output would be byte-identical leaves the file (and its mtime) untouched, so that a
// build system with `restat` (Ninja) or an mtime comparison (Make) does no downstream work.
#pragma once

#include <filesystem>

#include "formats/writer/asset_writer.hpp"

namespace clothbake::formats {

// True if `path` is a regular file whose size and every byte equal the asset write_asset would
// produce from `sections`. Streams the comparison (no copy of the asset in memory) and stops at
// the first differing chunk. False for a missing or unreadable file; never throws for I/O errors
// (the caller then writes the file, which reports them). Error(Internal) for invalid sections.
bool file_holds_asset(const std::filesystem::path& path, SectionRefs sections);

}  // namespace clothbake::formats

// Bridges the exception-free reader to clothbake's error type for the C++20 tools.
#pragma once

#include <string>

#include "common/error.hpp"
#include "formats/reader/asset.hpp"
#include "formats/validate/checksums.hpp"

namespace clothbake::formats {

// The process exit code for a reader failure: Io -> Input (2), InvalidArgument -> Internal (4),
// everything about the bytes (not an asset, truncated, corrupt, wrong version...) -> InvalidAsset
// (3).
ExitCode exit_code_of(const reader::Status& status);

// "CBK-E012: MESSAGE" (or MESSAGE when there is no check ID).
std::string describe(const reader::Status& status);

// Throws clothbake::Error for a failed reader call on an opened asset: Input (2) for NotFound (the
// asset lacks a section the command needs), exit_code_of() otherwise; the message is
// "CONTEXT: " + describe(). Returns when the status is Ok.
void throw_if_failed(const reader::Status& status, const std::string& context);

// How much open_asset verifies: the structure only (Asset::open), or also every checksum
// (reader::verify_checksums: reads every byte once).
enum class Verify { Structure, Checksums };

// Opens an asset (structure, and with Verify::Checksums every checksum: checksums.hpp) or throws
// clothbake::Error with exit_code_of() and describe(); the message starts with the path.
reader::Asset open_asset(const std::string& path, Verify verify);

}  // namespace clothbake::formats

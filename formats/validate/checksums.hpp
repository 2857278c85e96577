// Checksum verification of an opened asset (docs/format.md, "Checksums"): the header checksum
// (XXH64 of header bytes [0, 56) and the section table) and each section's payload checksum.
// Asset::open checks structure only and reads no payload byte; a tool that must know the bytes
// are the ones the writer wrote (clothbake's commands do, before anything else) calls these.
//
// C++17, standard library only, noexcept, no allocation. Safe on any asset that Asset::open
// accepted: every range hashed is one open() has bounds-checked. Thread-safe (reads only).
// Part of the opt-in library clothbake_reader_validate; a renderer that trusts its assets links
// the reader core alone.
#pragma once

#include <cstdint>

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

// The header checksum. Corrupt (CBK-E004, Check::HeaderChecksum) when it differs, naming both
// values; InvalidArgument when the asset is not open.
Status verify_header_checksum(const Asset& asset) noexcept;

// One section's payload checksum, read from the table (only section.index is used, so a
// modified SectionInfo cannot point outside). Corrupt (CBK-E012, Check::SectionChecksum) naming
// the section and both values; InvalidArgument for a closed asset or an index out of range.
Status verify_section(const Asset& asset, const SectionInfo& section) noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
// The header checksum, then every section's in table order; the first failure. O(file size).
Status verify_checksums(const Asset& asset) noexcept;
#endif

}  // namespace clothbake::reader

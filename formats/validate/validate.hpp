// Deep validation of an opened asset: everything open() checks is already true; this adds every
// section checksum (all of them, not just the first failure), zero padding and reserved bytes,
// NaN/Inf in every floating-point section, the layout and value ranges of the sections this
// reader interprets, and the views of the baked tables (parallax, visibility, clusters, raw and
// compressed Integral-Radiance tables) opened as a renderer opens them, with their consistency
// against each other and the feature maps. Each finding carries a stable check ID (docs/format.md,
// "Validation checks").
//
// C++17, standard library only, noexcept; allocates only through the reader's decoders (the coded
// maps, the compressed tables, the compressed parallax: nothrow, a failed allocation is reported,
// not thrown); reads every byte of the asset once or twice. Safe on untrusted assets (that open()
// accepted). An opt-in library (clothbake_reader_validate): a renderer needs only the reader.
#pragma once

#include <cstdint>

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

inline constexpr uint32_t kNoSection = 0xffffffffu;

// CBK-E022 (Check::CrossSection): sections that are each well formed but disagree with each other
// (a table's cluster count against the label map's, a compressed texel's cluster against its
// label, a raw table with values outside its cluster's texels, a parallax SAT that is not the SAT
// of the depth codes, raw and compressed tables of one kind with different shapes).
inline constexpr Check kCheckCrossSection = Check::CrossSection;

// Called once per finding. `section` is the table index or kNoSection; `message` is only valid
// during the call.
using FindingCallback = void (*)(void* user, Check check, uint32_t section, const char* message);

struct ValidationSummary {
  uint32_t errors = 0;
  uint32_t warnings = 0;
};

// Runs every check on an open asset, the header checksum and every section checksum included
// (each failure is a finding). `callback` may be null.
ValidationSummary validate_asset(const Asset& asset, FindingCallback callback, void* user) noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // the tools' listing
// Convenience: reports the open() failure of a file as a finding (for a uniform listing).
inline ValidationSummary report_open_failure(const Status& status, FindingCallback callback,
                                             void* user) noexcept {
  if (callback) callback(user, status.check(), kNoSection, status.message());
  return ValidationSummary{1, 0};
}
#endif

}  // namespace clothbake::reader

// The stamps of `clothbake batch` (docs/batch.md, "Batch"): per fabric, a JSON file in
// OUTDIR/.clothbake-batch/ recording what its last successful bake read and wrote, and the check
// that decides whether the fabric is up to date. A stamp is clothbake's own file but may be
// damaged or edited: every check here is safe on any bytes (fuzzed: tests/fuzz/batch_stamp_fuzzer).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace clothbake::cli {

// What a stamp must name for its fabric to be up to date: the tool, the executable, the options
// that change an asset's bytes, the fabric and the output paths (paths are bytes).
struct StampKey {
  std::string tool, exe, options, fabric, output;
};

struct StampCheck {
  bool up_to_date = false;
  std::string why;              // when not up to date: "another clothbake", "PATH changed", ...
  uint64_t peak_rss_bytes = 0;  // the last bake's measured peak (0 when the stamp has none)
  uint64_t output_size = 0;     // the output's size, when up to date
};

// A JSON value that must be a whole number in [0, 2^64) (unsigned) or in [-2^63, 2^63) (signed):
// the number itself; anything else (a string, a fraction, a number beyond the type, which JSON
// parses as a double whose conversion would be undefined) throws std::invalid_argument naming
// `what`. For stamps and bake reports read back from files.
uint64_t json_unsigned(const nlohmann::json& value, const char* what);
int64_t json_signed(const nlohmann::json& value, const char* what);

// Whether the stamp `text` holds for `key`: same tool, executable, options and fabric; the output
// with the stamped size and mtime; every input the bake read with its stamped size and mtime, or,
// when only the mtime changed, its stamped XXH64 (a changed size is a change; only touched files
// are hashed). Text that is not a stamp (not JSON, values of other types, not UTF-8) reads as "not
// up to date" ("unreadable stamp"), never as an error. Reads only the files the stamp names.
StampCheck check_stamp(std::string_view text, const StampKey& key);

// The stamp text of a bake that wrote `key.output`, from its --report JSON (`report["inputs"]`
// and `report["total"]`). JSON replaces bytes that are not UTF-8, so the fabric's and the scene's
// paths (roles "fabric" and "scene") are taken from `key.fabric` and `scene` instead; every path
// is stored so that it reads back byte for byte. Throws nlohmann::json::exception when the report
// lacks those keys.
std::string make_stamp(const StampKey& key, const std::string& scene, const nlohmann::json& report);

}  // namespace clothbake::cli

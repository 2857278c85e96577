// WIF 1.1 (Weaving Information File) import: a weaving draft turned into a weave matrix with thread
// colours, spacings and thicknesses (docs/weaves.md lists the subset read and how each ambiguity of
// the specification is resolved).
//
// The drawdown: for pick p and end e the warp is up iff the shafts lifted on pick p (its [LIFTPLAN]
// entry, or the [TIE-UP] of the treadles pressed in its [TREADLING] entry) include a shaft that end
// e is threaded on ([THREADING]); a sinking shed (Rising Shed=false) inverts the result.
//
// Safe on untrusted input: every malformed or unweavable draft throws clothbake::Error with
// ExitCode::Input and a message "PATH: [SECTION] line N: ..." (or naming the section when the
// problem is a missing section or key); sizes are bounded (weave::kMaxRepeat threads, shafts and
// treadles <= kMaxWifShafts) before anything proportional to them is allocated.
#pragma once

#include <string>
#include <vector>

#include "bake/inputs/weave_maps.hpp"

namespace clothbake {

// Largest shaft or treadle count accepted.
inline constexpr int kMaxWifShafts = 256;

struct WifDraft {
  weave::WeaveSpec spec;              // matrix (picks x ends), colours (linear RGB), geometry (mm)
  std::string title;                  // [TEXT] Title, or empty
  std::vector<std::string> warnings;  // also reported through clothbake::warn()
  std::string version;                // [WIF] Version, e.g. "1.1"
  std::string source_program;         // [WIF] Source Program, or empty
  int shafts = 0, treadles = 0;       // [WEAVING]
  bool rising_shed = true;            // [WEAVING] Rising Shed (default true)
  bool from_liftplan = false;         // true if the lifts came from [LIFTPLAN]
  // 0-based shafts each end is threaded on (empty = unthreaded), size ends.
  std::vector<std::vector<int>> threading;
  // 0-based shafts lifted on each pick (after tie-up and treadling), size picks.
  std::vector<std::vector<int>> lifts;
};

// Reads and parses a WIF file. Throws Error(Input) if the file cannot be read (naming the path) or
// for anything parse_wif rejects.
WifDraft read_wif(const std::string& path);
// Parses WIF text; `path_for_messages` prefixes every message. Throws Error(Input) naming the
// section and line of the problem.
WifDraft parse_wif(const std::string& text, const std::string& path_for_messages);

}  // namespace clothbake

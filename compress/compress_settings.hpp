// What the bake asks of the compression stage: on/off, keep the raw tables or not, and either a
// fixed C-PCA shape (--compress k,r) or a target error (--max-error E) for which the stage picks
// the ranks itself. docs/compression.md explains the defaults (measured on the example fabrics).
//
// C++20. parse_* throw clothbake::Error(Usage) naming the option on bad text.
#pragma once

#include <cstdint>
#include <string>

#include "compress/cpca.hpp"

namespace clothbake {
struct BakeSettings;
}

namespace clothbake::compress {

// Default target: relative RMS error of the stored texel values (1-texel footprints). Footprints
// of 4^2 texels and larger then measure below 1 % on the example fabrics (docs/compression.md).
inline constexpr double kDefaultMaxError = 0.008;
// Rank cap per C-PCA cluster in target mode.
inline constexpr int kDefaultRankCap = 64;

// Name of the optional pipeline artifact (a CompressSettings) the bake command seeds from
// --compress / --max-error / --keep-raw / --no-compress; without it the stage uses
// settings_from_bake(fabric.bake).
inline constexpr const char* kCompressSettingsArtifact = "compress_options";

struct CompressSettings {
  bool enabled = true;         // write compressed tables
  bool keep_raw = false;       // also keep the raw tables in the asset
  bool fixed = false;          // true: exactly (clusters, rank); false: ranks for max_error
  int clusters = 1;            // C-PCA clusters per visibility cluster (k)
  int rank = kDefaultRankCap;  // rank per C-PCA cluster (fixed) or the cap (target mode)
  double max_error = kDefaultMaxError;
  uint64_t seed = 1;

  CpcaOptions cpca() const;
  std::string describe() const;  // "C-PCA k=1, ranks for 2% (cap 64)" / "C-PCA k=4, r=10"
};

// From a fabric's [bake] settings: `compress` switches compression on or off; the C-PCA shape is
// the target-error default (the fabric format's compress_clusters / compress_rank keep the
// paper's 4 / 10 as defaults, which miss the error target on narrow lobes, so they are used only
// when the bake passes --compress, see docs/compression.md).
CompressSettings settings_from_bake(const BakeSettings& bake);

// "k,r" (e.g. "4,10") -> fixed settings. Throws Error(Usage) naming `option` otherwise.
CompressSettings parse_compress_shape(const std::string& text, const std::string& option);

}  // namespace clothbake::compress

// What the bake asks of the compression stage: on/off, keep the raw tables or not, and either a
// fixed C-PCA shape (--compress k,r) or a target error (--max-error E) for which the stage picks
// the ranks itself. docs/compression.md explains the defaults (measured on the example fabrics).
//
// C++20. check_compress_request throws clothbake::Error(Usage) naming the options.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace clothbake {
struct BakeSettings;
}

namespace clothbake::compress {

// compress/cpca.hpp (declared here only: that header brings Eigen into every command-line source
// that names a compression setting).
struct CpcaOptions;

// Default target: relative RMS error of the stored texel values (1-texel footprints). Footprints
// of 4^2 texels and larger then measure below 1 % on the example fabrics (docs/compression.md).
inline constexpr double kDefaultMaxError = 0.008;
// The largest C-PCA shape a bake accepts: rank per cluster, clusters per visibility cluster.
inline constexpr int kMaxCpcaRank = 255;
inline constexpr int kMaxCpcaClustersPerStratum = 64;
// Rank cap per C-PCA cluster in target mode.
inline constexpr int kDefaultRankCap = 64;

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

// From a fabric's [bake] settings: `compress` switches compression on or off;
// `compress_rank` > 0 asks for a fixed C-PCA shape (k = compress_clusters, or 1 when that is 0);
// compress_rank = 0 (the default) means "auto": the stage picks the ranks for kDefaultMaxError
// (k = compress_clusters, or 1 when 0). docs/fabric-format.md, docs/compression.md.
CompressSettings settings_from_bake(const BakeSettings& bake);

// What the bake command line asks of the compression stage. Unset fields fall back on the
// fabric's [bake] settings (settings_from_bake).
struct CompressRequest {
  bool disable = false;             // --no-compress: raw tables only
  bool keep_raw = false;            // --keep-raw: compressed and raw tables
  std::optional<int> clusters;      // --compress K,R: fixed shape...
  std::optional<int> rank;          // ...(both set or neither)
  std::optional<double> max_error;  // --max-error E: target mode, the stage picks the ranks
  // Option names given, in command-line spelling, for messages ("--compress", ...).
  std::vector<std::string> given() const;
};

// Throws Error(Usage) naming both options for a conflicting request: --no-compress with any of
// the others, --compress with --max-error; and for --max-error outside (0, 1].
void check_compress_request(const CompressRequest& request);

// The settings a bake uses: the fabric's [bake] settings overridden by what the request sets.
// --max-error keeps the fabric's compress_clusters (or 1) and caps ranks at kDefaultRankCap.
CompressSettings resolve_compress_settings(const BakeSettings& bake,
                                           const CompressRequest& request);

}  // namespace clothbake::compress

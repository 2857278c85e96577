// Compression settings (compress_settings.hpp).
#include "compress/compress_settings.hpp"

#include <cstdio>
#include <regex>

#include "bake/inputs/fabric.hpp"
#include "common/error.hpp"

namespace clothbake::compress {

CpcaOptions CompressSettings::cpca() const {
  CpcaOptions o;
  o.clusters_per_stratum = clusters;
  o.rank = rank;
  o.target_error = fixed ? 0.0 : max_error;
  o.seed = seed;
  return o;
}

std::string CompressSettings::describe() const {
  char text[128];
  if (!enabled) return "raw tables only";
  if (fixed)
    std::snprintf(text, sizeof text, "C-PCA k=%d, r=%d", clusters, rank);
  else
    std::snprintf(text, sizeof text, "C-PCA k=%d, ranks for %.3g%% (cap %d)", clusters,
                  max_error * 100.0, rank);
  return text;
}

CompressSettings settings_from_bake(const BakeSettings& bake) {
  CompressSettings s;
  s.enabled = bake.compress;
  s.seed = bake.seed;
  return s;
}

CompressSettings parse_compress_shape(const std::string& text, const std::string& option) {
  static const std::regex shape(R"(\s*(\d{1,3})\s*,\s*(\d{1,3})\s*)");
  std::smatch m;
  if (!std::regex_match(text, m, shape))
    throw Error(ExitCode::Usage, option +
                                     " expects K,R (C-PCA clusters per visibility cluster and "
                                     "rank, e.g. 1,24), got '" +
                                     text + "'");
  CompressSettings s;
  s.fixed = true;
  s.clusters = std::stoi(m[1].str());
  s.rank = std::stoi(m[2].str());
  if (s.clusters < 1 || s.clusters > kMaxCpcaClustersPerStratum)
    throw Error(ExitCode::Usage, option + ": K must be in [1, " +
                                     std::to_string(kMaxCpcaClustersPerStratum) + "], got " +
                                     m[1].str());
  if (s.rank < 0 || s.rank > kMaxCpcaRank)
    throw Error(ExitCode::Usage, option + ": R must be in [0, " + std::to_string(kMaxCpcaRank) +
                                     "], got " + m[2].str());
  return s;
}

}  // namespace clothbake::compress

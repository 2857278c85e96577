// Compression settings (compress_settings.hpp).
#include "compress/compress_settings.hpp"
#include "compress/cpca.hpp"

#include <cstdio>

#include "common/error.hpp"
#include "fabric/fabric.hpp"

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
  s.clusters = bake.compress_clusters > 0 ? bake.compress_clusters : 1;
  if (bake.compress_rank > 0) {
    s.fixed = true;
    s.rank = bake.compress_rank;
  }
  return s;
}

std::vector<std::string> CompressRequest::given() const {
  std::vector<std::string> out;
  if (disable) out.push_back("--no-compress");
  if (clusters || rank) out.push_back("--compress");
  if (max_error) out.push_back("--max-error");
  if (keep_raw) out.push_back("--keep-raw");
  return out;
}

void check_compress_request(const CompressRequest& request) {
  if (request.clusters.has_value() != request.rank.has_value())
    throw_internal_error("compress request: clusters and rank must be set together");
  if (request.disable)
    for (const std::string& other : request.given())
      if (other != "--no-compress")
        throw Error(ExitCode::Usage, "--no-compress conflicts with " + other +
                                         " (it bakes raw tables only; drop one of the two)");
  if (request.clusters && request.max_error)
    throw Error(ExitCode::Usage,
                "--compress conflicts with --max-error (a fixed C-PCA shape, or a target error "
                "for which the ranks are chosen: give one of the two)");
  if (request.max_error && !(*request.max_error > 0.0 && *request.max_error <= 1.0))
    throw Error(ExitCode::Usage, "--max-error expects a relative RMS error in (0, 1], got " +
                                     std::to_string(*request.max_error));
}

CompressSettings resolve_compress_settings(const BakeSettings& bake,
                                           const CompressRequest& request) {
  check_compress_request(request);
  CompressSettings s = settings_from_bake(bake);
  if (request.disable) s.enabled = false;
  if (request.clusters) {
    s.enabled = true;
    s.fixed = true;
    s.clusters = *request.clusters;
    s.rank = *request.rank;
  }
  if (request.max_error) {
    s.enabled = true;
    s.fixed = false;
    s.max_error = *request.max_error;
    s.rank = kDefaultRankCap;
  }
  // --keep-raw alone does not switch on what the fabric switched off ([bake] compress = false
  // already keeps the raw tables).
  if (request.keep_raw) s.keep_raw = true;
  return s;
}

}  // namespace clothbake::compress

// Verification of an asset's raw Integral-Radiance tables against the fabric they were baked from
// (`clothbake verify`; docs/tables.md, "Verification").
//
// For random footprints of every size class (footprint_sampling.hpp) and random half vectors h,
// for every table kind in the asset and every cluster, it recomputes from the fabric:
//  (a) SAT error: the table's answer F_c(R, h) against the direct sum, over the texels covered by
//      R (with their covered area, tiles wrapped), of the same per-texel bin values (the bake's
//      own quadrature: radiance_bin_values with the asset's samples per bin) weighted by the same
//      bilinear bin weights, masked by the asset's label map;
//  (b) directional error (specular tables): F_c(R, h) against the exact sum of I(x) D_x(h) over
//      the same texels: what binning the half vector (bin averages, bilinear between bin centres)
//      costs, largest for narrow lobes (roughness below the 2-sigma limit of the bins).
// Both errors are relative: |F - reference| / max(reference, A * level), A the footprint area in
// texels and level the cluster's mean texel value over the tile (for the same bins, resp. the same
// h), so that footprints dimmer than the cluster's average are measured against that average
// rather than against a value that may be arbitrarily close to zero (docs/tables.md explains why a
// 4-byte table cannot promise more, and what a pure relative error shows).
//
// C++20. Errors: clothbake::Error(InvalidAsset) when the asset lacks the label map or the tables
// the fabric needs, or they are malformed; Error(Input) when the fabric does not match the asset
// (resolution, cluster labels).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"
#include "formats/reader/asset.hpp"

namespace clothbake::verify {

// Exit code of `clothbake verify` when a measured error exceeds its threshold.
inline constexpr int kVerificationFailedExitCode = 5;

struct RadianceVerifyOptions {
  int samples = 140;  // footprints per table kind (spread over the size classes)
  uint64_t seed = 1;
  double max_rel_error = 1e-5;          // threshold of (a)
  std::optional<double> max_dir_error;  // threshold of (b); none: reported only
};

struct ErrorStats {
  std::string size_class;
  int footprints = 0;
  int values = 0;         // footprint x cluster comparisons
  double max = 0.0;       // largest relative error
  double rms = 0.0;       // root mean square of the relative errors
  double max_pure = 0.0;  // largest |F - ref| / ref among values with ref >= A * level
};

struct KindReport {
  std::string kind;  // "specular", "gap"
  int resolution = 0, bins_per_side = 0, clusters = 0, stored_clusters = 0;
  int samples_per_bin_side = 0, element_bits = 0;
  double min_roughness = 0.0;
  int bins_needed = 0;                  // 2-sigma rule
  std::vector<ErrorStats> sat;          // (a), per size class
  std::vector<ErrorStats> directional;  // (b), per size class (empty for the gap table)
  double sat_max = 0.0, directional_max = 0.0;
  std::string worst_sat;  // the footprint, cluster and h of the largest (a) error
};

struct RadianceVerifyReport {
  std::vector<KindReport> kinds;
  double max_rel_error = 0.0;
  std::optional<double> max_dir_error;
  bool passed = true;
  std::vector<std::string> failures;  // one line per exceeded threshold
};

// Runs the checks (deterministic for a seed). Throws as documented above.
RadianceVerifyReport verify_radiance(const reader::Asset& asset, const Fabric& fabric,
                                     const RadianceVerifyOptions& options);

nlohmann::json report_json(const RadianceVerifyReport& report);
std::string report_text(const RadianceVerifyReport& report);

}  // namespace clothbake::verify

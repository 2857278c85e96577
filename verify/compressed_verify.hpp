// Verification of an asset's C-PCA compressed Integral-Radiance tables against the raw tables
// (`clothbake verify`, docs/compression.md "Verify"). The raw reference is the asset's own raw
// tables when it keeps them (exact texel values from the fixed-point SATs, what the compress stage
// started from), else recomputed from the fabric with the asset's label map and quadrature.
//
// Per table kind it reports:
//  - per table (cluster, bin): RMSE over the tile's texels, maximum error and PSNR
//    (20 log10(peak / RMSE), peak = the raw table's largest texel value), with a summary (worst
//    RMSE relative to peak, lowest and median PSNR) and the kind's relative RMS texel error;
//  - per footprint-size class (verify/footprint_sampling.hpp: 1, 2, 4, 16, 64 texels per side,
//    one tile, many tiles) on random footprints and half vectors: the RMS relative error
//    sqrt(sum (F - F_ref)^2 / sum F_ref^2) over every (footprint, cluster), the same for the sum
//    over clusters, and the largest relative error |F - F_ref| / max(F_ref, A * level) (level:
//    the cluster's mean texel value for the same bins, as in radiance_verify.hpp);
//  - the compression ratio against raw float tables (stored clusters x bins x N^2 x 4 bytes) and
//    the bytes the reader decodes into memory;
//  - query throughput on one thread (thread CPU time, so that other processes on the machine do
//    not count): compressed try_query_all against raw try_query_all on the same footprints (the
//    asset's raw tables when kept, else raw tables built in memory from the fabric);
//  - the footprint side below which the compressed tables should not be used (the smallest class
//    side from which every larger class meets the footprint threshold): a renderer evaluates the
//    texels directly below it.
// Thresholds: footprint RMS relative error for classes of side >= threshold_side, optionally a
// minimum compression ratio and a maximum relative RMS texel error; `passed` is false (and
// `failures` says why) when one is exceeded.
//
// C++20. Errors: clothbake::Error(InvalidAsset) for an asset without compressed tables or label
// map, or with malformed ones; Error(Input) when the fabric does not match the asset.
#pragma once

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"
#include "formats/reader/asset.hpp"

namespace clothbake::verify {

struct CompressedVerifyOptions {
  int samples = 1400;  // footprints per kind, spread over the size classes
  uint64_t seed = 1;
  double max_footprint_error = 0.01;      // RMS relative footprint error threshold...
  double threshold_side = 4.0;            // ...for the classes whose sides are >= this (texels)
  std::optional<double> min_ratio;        // fail below this compression ratio
  std::optional<double> max_texel_error;  // fail above this relative RMS texel error
  bool throughput = true;                 // measure queries/s (builds raw tables if not kept)
  int throughput_queries = 100000;
};

// PSNR reported for a table decompressed without any error (JSON has no infinity).
inline constexpr double kExactPsnrDb = 999.0;

struct TableErrorSummary {
  uint64_t tables = 0;               // (cluster, bin) tables with a non-zero raw texel
  double worst_relative_rmse = 0.0;  // max over tables of RMSE / peak
  std::string worst_table;           // "cluster C bin B"
  double min_psnr_db = 0.0, median_psnr_db = 0.0;  // kExactPsnrDb when the tables are exact
  double max_abs_error = 0.0;                      // over every texel of every table
  double texel_rms_relative = 0.0;                 // sqrt(sum err^2 / sum ref^2) over all tables
};

struct FootprintClassError {
  std::string size_class;
  double min_side = 0.0;
  int footprints = 0;
  double rms_relative = 0.0;      // per (footprint, cluster)
  double rms_relative_sum = 0.0;  // of the sum over clusters
  double max_relative = 0.0;      // guarded by the cluster level
};

struct CompressedKindReport {
  std::string kind;
  int resolution = 0, bins_per_side = 0, clusters = 0, cells = 0, images = 0;
  int min_rank = 0, max_rank = 0;
  uint64_t compressed_bytes = 0, raw_float_bytes = 0, decoded_bytes = 0;
  double ratio = 0.0;
  double bake_error = 0.0;  // what the asset claims (info record)
  // The raw reference: the asset's own raw tables (true) or recomputed from the fabric (false).
  bool raw_reference_from_asset = false;
  TableErrorSummary tables;
  std::vector<FootprintClassError> classes;
  // Smallest class side from which every class meets the threshold (infinity: none does).
  double min_reliable_side = std::numeric_limits<double>::infinity();
  bool throughput_measured = false;
  bool raw_from_asset = false;
  double compressed_queries_per_second = 0.0, raw_queries_per_second = 0.0;
  double cost_ratio = 0.0;  // compressed time per query / raw time per query
};

struct CompressedVerifyReport {
  std::vector<CompressedKindReport> kinds;
  CompressedVerifyOptions options;
  bool passed = true;
  std::vector<std::string> failures;
};

// True when the asset holds compressed (resp. raw) Integral-Radiance tables of some kind (their
// info section is present; whether they are well formed is for the readers' open() to say).
bool has_compressed_tables(const reader::Asset& asset);
bool has_raw_tables(const reader::Asset& asset);

// Runs the comparison (deterministic for a seed, except the measured throughput).
CompressedVerifyReport verify_compressed(const reader::Asset& asset, const Fabric& fabric,
                                         const CompressedVerifyOptions& options);

nlohmann::json compressed_report_json(const CompressedVerifyReport& report);
std::string compressed_report_text(const CompressedVerifyReport& report);

}  // namespace clothbake::verify

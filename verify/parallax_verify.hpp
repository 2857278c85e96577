// Verification of an asset's compressed parallax table against the raw one (`clothbake verify`,
// docs/compression.md "Compressed parallax", "Verify"). The raw reference is the asset's own raw
// table when it keeps one (`--keep-raw`), else the table recomputed from the fabric by the same ray
// casting as the bake (raycast::bake_parallax at the compressed table's directions and cap), held
// in memory with its SATs.
//
// Everything is measured as the error a renderer sees: the Eq. 2 offset (r / o.z)(o.x, o.y), in
// texels (times N).
//  - per texel and bin centre (every texel, every direction): |offset_compressed - offset_raw| =
//    |r_c - r_raw| N tan(theta_d); RMS, maximum, and the share of entries above 0.25 texel;
//  - per footprint-size class (verify/footprint_sampling.hpp: 1, 2, 4, 16, 64 texels per side, one
//    tile, many tiles) on random footprints and view directions (the sampled upper-hemisphere
//    vectors, clamped onto the cap as every query does): |offset of the compressed footprint mean
//    - offset of the raw footprint mean|, RMS and maximum per class;
//  - the size ratio: the raw form's bytes (16-bit codes + u32 SATs + info, what an uncompressed
//  bake stores)
//    over the compressed sections' stored bytes.
// Thresholds (each optional except the two defaults, the targets of docs/performance.md): RMS
// per-texel error (default 0.05 texel), maximum, share above 0.25 texel, RMS footprint error of
// the classes of side >= footprint_min_side (default 0.02 texel for >= 4 texels), minimum ratio.
//
// C++20. Errors: clothbake::Error(InvalidAsset) for an asset whose compressed parallax does not
// open; Error(Input) when the fabric does not match the asset (resolution).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"
#include "formats/reader/asset.hpp"

namespace clothbake::verify {

struct ParallaxVerifyOptions {
  int samples = 1400;  // random footprints, spread over the size classes
  uint64_t seed = 1;
  double max_rms_error = 0.05;            // per-texel RMS offset error, texels
  std::optional<double> max_error;        // per-texel maximum, texels
  std::optional<double> max_share_above;  // share of entries above 0.25 texel, [0, 1]
  double max_footprint_error = 0.02;      // RMS footprint offset error, texels...
  double footprint_min_side = 4.0;        // ...of the classes whose sides are >= this
  std::optional<double> min_ratio;        // raw bytes / compressed bytes
};

struct ParallaxClassError {
  std::string size_class;
  double min_side = 0.0;
  int footprints = 0;
  double rms_error = 0.0;  // texels
  double max_error = 0.0;  // texels
};

struct ParallaxVerifyReport {
  int resolution = 0, dirs = 0;
  double min_cos = 0.0;
  int bits = 0;                           // of the compressed codes
  std::string section;                    // "parallax_entropy"
  bool raw_reference_from_asset = false;  // false: recomputed from the fabric
  uint64_t entries = 0;                   // texels x directions
  double rms_error = 0.0, max_error = 0.0, share_above_quarter = 0.0;  // per texel, texels
  double max_depth_error = 0.0;                                        // tile-side units
  std::vector<ParallaxClassError> classes;
  uint64_t compressed_bytes = 0, raw_bytes = 0;
  double ratio = 0.0;
  ParallaxVerifyOptions options;
  bool passed = true;
  std::vector<std::string> failures;
};

// True when the asset holds a compressed parallax table (any of its sections is present).
bool has_compressed_parallax(const reader::Asset& asset);

// Runs the comparison (deterministic for a seed and any thread count).
ParallaxVerifyReport verify_parallax(const reader::Asset& asset, const Fabric& fabric,
                                     const ParallaxVerifyOptions& options);

nlohmann::json parallax_report_json(const ParallaxVerifyReport& report);
std::string parallax_report_text(const ParallaxVerifyReport& report);

}  // namespace clothbake::verify

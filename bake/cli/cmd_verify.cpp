// clothbake verify ASSET --fabric FABRIC.toml [--json] [--samples N] [--seed S]
//   raw tables:        [--max-rel-error E] [--max-dir-error E]
//   compressed tables: [--max-footprint-error E] [--footprint-min-side S] [--min-ratio R]
//                      [--max-texel-error E] [--compressed-samples N] [--no-throughput]
//   compressed parallax: [--max-parallax-rms-error E] [--max-parallax-error E]
//                      [--max-parallax-share-above S] [--max-parallax-footprint-error E]
//                      [--parallax-footprint-min-side S] [--min-parallax-ratio R]
//                      [--parallax-samples N] [--no-parallax]
//
// Checks what the asset holds against the fabric it was baked from:
//  - raw Integral-Radiance tables (when kept): SAT answers against direct summation over the same
//    texels and bins, and binned against exact per-texel D(h) (verify/radiance_verify.hpp,
//    docs/tables.md);
//  - C-PCA compressed tables (when present): decompressed against the asset's own raw tables when
//    it keeps them, else raw tables recomputed from the fabric with the asset's label map and
//    quadrature: per-table RMSE / max / PSNR, footprint
//    error per size class, ratio, compressed vs raw query throughput, and the footprint side below
//    which a renderer should evaluate texels directly (verify/compressed_verify.hpp,
//    docs/compression.md "Verify");
//  - the compressed parallax table (when present): per-texel and footprint Eq. 2 offset errors in
//    texels against the asset's raw table when kept, else the table recomputed from the fabric,
//    and the size ratio (verify/parallax_verify.hpp, docs/compression.md "Compressed parallax").
// Exit codes: 0 passed, 5 a threshold exceeded (verification failed), 3 the asset is unreadable
// or holds nothing to verify (no Integral-Radiance tables, raw or compressed, and no compressed
// parallax), 2 bad fabric or a fabric that does not match the asset, 1 usage.
#include <iostream>
#include <memory>
#include <optional>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "formats/reader/radiance_layout.hpp"
#include "formats/writer/open_asset.hpp"
#include "verify/compressed_verify.hpp"
#include "verify/parallax_verify.hpp"
#include "verify/radiance_verify.hpp"

namespace clothbake::cli {
namespace {

struct VerifyOptions {
  std::string asset;
  std::string fabric;
  bool json = false;
  uint64_t seed = 1;
  // Raw tables.
  double max_rel_error = 1e-5;
  double max_dir_error = 0;  // 0: not given
  int samples = 140;
  // Compressed tables.
  double max_footprint_error = verify::CompressedVerifyOptions{}.max_footprint_error;
  double footprint_min_side = verify::CompressedVerifyOptions{}.threshold_side;
  double min_ratio = 0;        // 0: not given
  double max_texel_error = 0;  // 0: not given
  int compressed_samples = verify::CompressedVerifyOptions{}.samples;
  bool no_throughput = false;
  // Compressed parallax.
  verify::ParallaxVerifyOptions parallax;
  double max_parallax_error = 0;         // 0: not given
  double max_parallax_share_above = -1;  // < 0: not given
  double min_parallax_ratio = 0;         // 0: not given
  bool no_parallax = false;
};

Action setup_verify(CLI::App& app) {
  auto o = std::make_shared<VerifyOptions>();
  add_asset_argument(app, o->asset, "asset to verify (.cbk)");
  app.add_option("--fabric", o->fabric, "the fabric description the asset was baked from")
      ->required();
  add_json_flag(app, o->json, "print the report as JSON on stdout");
  app.add_option("--seed", o->seed, "seed of the footprint sampling (default 1)");
  app.add_option("--max-rel-error", o->max_rel_error,
                 "raw tables: largest SAT-vs-direct-sum relative error accepted (default 1e-5)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-dir-error", o->max_dir_error,
                 "raw tables: largest binned-vs-exact D(h) relative error accepted (default: "
                 "report only)")
      ->check(CLI::PositiveNumber);
  app.add_option("--samples", o->samples,
                 "raw tables: random footprints per table kind (default 140)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--max-footprint-error", o->max_footprint_error,
                 "compressed tables: largest RMS relative footprint error accepted for footprints "
                 "of side >= --footprint-min-side (default 0.01)")
      ->check(CLI::PositiveNumber);
  app.add_option("--footprint-min-side", o->footprint_min_side,
                 "compressed tables: smallest footprint side (texels) held to "
                 "--max-footprint-error (default 4)")
      ->check(CLI::Range(1.0, 1e9));
  app.add_option("--min-ratio", o->min_ratio,
                 "compressed tables: smallest compression ratio accepted (default: report only)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-texel-error", o->max_texel_error,
                 "compressed tables: largest relative RMS texel error accepted (default: report "
                 "only)")
      ->check(CLI::PositiveNumber);
  app.add_option("--compressed-samples", o->compressed_samples,
                 "compressed tables: random footprints per table kind (default 1400)")
      ->check(CLI::Range(7, 1000000));
  app.add_flag("--no-throughput", o->no_throughput,
               "compressed tables: skip the compressed-vs-raw query throughput measurement");
  app.add_option("--max-parallax-rms-error", o->parallax.max_rms_error,
                 "compressed parallax: largest per-texel RMS Eq. 2 offset error accepted, texels "
                 "(default 0.05)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-parallax-error", o->max_parallax_error,
                 "compressed parallax: largest per-texel offset error accepted, texels (default: "
                 "report only)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-parallax-share-above", o->max_parallax_share_above,
                 "compressed parallax: largest share of (texel, direction) entries with an offset "
                 "error above 0.25 texel accepted, [0, 1] (default: report only)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--max-parallax-footprint-error", o->parallax.max_footprint_error,
                 "compressed parallax: largest RMS footprint-mean offset error accepted for "
                 "footprints of side >= --parallax-footprint-min-side, texels (default 0.02)")
      ->check(CLI::PositiveNumber);
  app.add_option("--parallax-footprint-min-side", o->parallax.footprint_min_side,
                 "compressed parallax: smallest footprint side (texels) held to "
                 "--max-parallax-footprint-error (default 4)")
      ->check(CLI::Range(1.0, 1e9));
  app.add_option("--min-parallax-ratio", o->min_parallax_ratio,
                 "compressed parallax: smallest raw/compressed size ratio accepted (default: "
                 "report only)")
      ->check(CLI::PositiveNumber);
  app.add_option("--parallax-samples", o->parallax.samples,
                 "compressed parallax: random footprints (default 1400)")
      ->check(CLI::Range(7, 1000000));
  app.add_flag("--no-parallax", o->no_parallax, "do not verify the compressed parallax table");
  return [o] {
    const reader::Asset asset = formats::open_asset(o->asset, formats::Verify::Checksums);
    const bool raw = verify::has_raw_tables(asset);
    const bool compressed = verify::has_compressed_tables(asset);
    const bool parallax = !o->no_parallax && verify::has_compressed_parallax(asset);
    if (!raw && !compressed && !parallax)
      throw Error(ExitCode::InvalidAsset,
                  o->asset +
                      ": the asset has nothing to verify: no Integral-Radiance tables, raw or "
                      "compressed, and no compressed parallax table (bake it with the tables "
                      "stage: without --stages, or with --stages tables,compress; or with the "
                      "parallax stage and compression on)");
    const Fabric fabric = load_fabric(o->fabric);

    std::optional<verify::RadianceVerifyReport> raw_report;
    if (raw) {
      verify::RadianceVerifyOptions options;
      options.samples = o->samples;
      options.seed = o->seed;
      options.max_rel_error = o->max_rel_error;
      if (o->max_dir_error > 0) options.max_dir_error = o->max_dir_error;
      raw_report = verify::verify_radiance(asset, fabric, options);
    }
    std::optional<verify::CompressedVerifyReport> compressed_report;
    if (compressed) {
      verify::CompressedVerifyOptions options;
      options.samples = o->compressed_samples;
      options.seed = o->seed;
      options.max_footprint_error = o->max_footprint_error;
      options.threshold_side = o->footprint_min_side;
      if (o->min_ratio > 0) options.min_ratio = o->min_ratio;
      if (o->max_texel_error > 0) options.max_texel_error = o->max_texel_error;
      options.throughput = !o->no_throughput;
      compressed_report = verify::verify_compressed(asset, fabric, options);
    }
    std::optional<verify::ParallaxVerifyReport> parallax_report;
    if (parallax) {
      verify::ParallaxVerifyOptions options = o->parallax;
      options.seed = o->seed;
      if (o->max_parallax_error > 0) options.max_error = o->max_parallax_error;
      if (o->max_parallax_share_above >= 0) options.max_share_above = o->max_parallax_share_above;
      if (o->min_parallax_ratio > 0) options.min_ratio = o->min_parallax_ratio;
      parallax_report = verify::verify_parallax(asset, fabric, options);
    }

    std::vector<std::string> failures;
    if (raw_report) failures = raw_report->failures;
    if (compressed_report)
      failures.insert(failures.end(), compressed_report->failures.begin(),
                      compressed_report->failures.end());
    if (parallax_report)
      failures.insert(failures.end(), parallax_report->failures.begin(),
                      parallax_report->failures.end());
    const bool passed = failures.empty();
    if (o->json) {
      // The raw-table report's keys at the top level (as before compression existed), the
      // compressed report under "compressed"; "passed" and "failures" cover both.
      nlohmann::json doc =
          raw_report ? verify::report_json(*raw_report)
                     : nlohmann::json{{"tables", nlohmann::json::array()},
                                      {"thresholds", {{"max_rel_error", o->max_rel_error}}}};
      doc["raw_tables_verified"] = raw;
      if (compressed_report) {
        const nlohmann::json c = verify::compressed_report_json(*compressed_report);
        doc["compressed"] = c["compressed"];
        doc["compressed_thresholds"] = c["thresholds"];
        doc["compressed_passed"] = c["passed"];
      } else {
        doc["compressed"] = nlohmann::json::array();
      }
      if (parallax_report)
        doc["parallax"] = verify::parallax_report_json(*parallax_report);
      else
        doc["parallax"] = {
            {"verified", false},
            {"reason",
             o->no_parallax ? "--no-parallax" : "the asset has no compressed parallax table"}};
      doc["passed"] = passed;
      doc["failures"] = failures;
      doc["asset"] = o->asset;
      doc["fabric"] = o->fabric;
      doc["samples"] = o->samples;
      doc["compressed_samples"] = o->compressed_samples;
      doc["seed"] = o->seed;
      doc["warnings"] = take_warnings();
      print_json(doc);
    } else {
      if (raw_report) std::cout << verify::report_text(*raw_report);
      if (compressed_report) std::cout << verify::compressed_report_text(*compressed_report);
      if (parallax_report) std::cout << verify::parallax_report_text(*parallax_report);
      if (!raw && compressed)
        std::cout << "raw tables: not in the asset (the compressed tables were compared with raw "
                     "tables recomputed from the fabric)\n";
      std::cout << (passed ? "verification passed" : "VERIFICATION FAILED") << "\n";
      std::cout.flush();
    }
    if (!passed) {
      for (const auto& f : failures)
        report_error("verification failed: " + f);
      return verify::kVerificationFailedExitCode;
    }
    return 0;
  };
}

const bool verify_registered = register_command(
    {"verify",
     "Check an asset's Integral-Radiance tables (raw and compressed) and compressed parallax "
     "against the fabric they came from",
     setup_verify});

}  // namespace
}  // namespace clothbake::cli

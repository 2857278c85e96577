// clothbake verify ASSET --fabric FABRIC.toml [--json] [--samples N] [--seed S]
//   raw tables:        [--max-rel-error E] [--max-dir-error E]
//   compressed tables: [--max-footprint-error E] [--footprint-min-side S] [--min-ratio R]
//                      [--max-texel-error E] [--compressed-samples N] [--no-throughput]
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
//    docs/compression.md "Verify").
// Exit codes: 0 passed, 5 a threshold exceeded (verification failed), 3 the asset is unreadable
// or holds no Integral-Radiance tables (raw or compressed), 2 bad fabric or a fabric that does not
// match the asset, 1 usage.
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
  return [o] {
    const reader::Asset asset = formats::open_asset(o->asset, reader::Verify::Checksums);
    const bool raw = verify::has_raw_tables(asset);
    const bool compressed = verify::has_compressed_tables(asset);
    if (!raw && !compressed)
      throw Error(ExitCode::InvalidAsset,
                  o->asset +
                      ": the asset has no Integral-Radiance tables, raw or compressed, to verify "
                      "(bake it with the tables stage: without --stages, or with --stages "
                      "tables,compress)");
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

    std::vector<std::string> failures;
    if (raw_report) failures = raw_report->failures;
    if (compressed_report)
      failures.insert(failures.end(), compressed_report->failures.begin(),
                      compressed_report->failures.end());
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
      if (!raw)
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

const bool registered = register_command(
    {"verify",
     "Check an asset's Integral-Radiance tables (raw and compressed) against the fabric they "
     "came from",
     setup_verify});

}  // namespace
}  // namespace clothbake::cli

// clothbake verify ASSET --fabric FABRIC.toml [--json] [--max-rel-error E] [--max-dir-error E]
// [--samples N] [--seed S]: recomputes the asset's Integral-Radiance tables from the fabric on
// random footprints (one texel to several tiles) and half vectors, and reports per footprint-size
// class (a) the SAT answer against direct summation over the same texels and bins and (b) the
// binned answer against the exact per-texel D(h) (verify/radiance_verify.hpp, docs/tables.md).
// Exit codes: 0 passed, 5 a threshold exceeded (verification failed), 3 the asset is unreadable
// or lacks the tables, 2 bad fabric or a fabric that does not match the asset, 1 usage.
#include <iostream>
#include <memory>
#include <optional>

#include "bake/cli/command.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "common/diagnostics.hpp"
#include "formats/writer/open_asset.hpp"
#include "verify/radiance_verify.hpp"

namespace clothbake::cli {
namespace {

struct VerifyOptions {
  std::string asset;
  std::string fabric;
  bool json = false;
  double max_rel_error = 1e-5;
  double max_dir_error = 0;  // 0: not given
  int samples = 140;
  uint64_t seed = 1;
};

Action setup_verify(CLI::App& app) {
  auto o = std::make_shared<VerifyOptions>();
  app.add_option("ASSET", o->asset, "asset to verify (.cbk)")->required();
  app.add_option("--fabric", o->fabric, "the fabric description the asset was baked from")
      ->required();
  app.add_flag("--json", o->json, "print the report as JSON on stdout");
  app.add_option("--max-rel-error", o->max_rel_error,
                 "largest SAT-vs-direct-sum relative error accepted (default 1e-5)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-dir-error", o->max_dir_error,
                 "largest binned-vs-exact D(h) relative error accepted (default: report only)")
      ->check(CLI::PositiveNumber);
  app.add_option("--samples", o->samples, "random footprints per table kind (default 140)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--seed", o->seed, "seed of the footprint sampling (default 1)");
  return [o] {
    const reader::Asset asset = formats::open_asset(o->asset, reader::Verify::Checksums);
    const Fabric fabric = load_fabric(o->fabric);
    verify::RadianceVerifyOptions options;
    options.samples = o->samples;
    options.seed = o->seed;
    options.max_rel_error = o->max_rel_error;
    if (o->max_dir_error > 0) options.max_dir_error = o->max_dir_error;
    const verify::RadianceVerifyReport report = verify::verify_radiance(asset, fabric, options);
    if (o->json) {
      nlohmann::json doc = verify::report_json(report);
      doc["asset"] = o->asset;
      doc["fabric"] = o->fabric;
      doc["samples"] = o->samples;
      doc["seed"] = o->seed;
      doc["warnings"] = take_warnings();
      print_json(doc);
    } else {
      std::cout << verify::report_text(report);
      std::cout.flush();
    }
    if (!report.passed) {
      for (const auto& f : report.failures)
        report_error("verification failed: " + f);
      return verify::kVerificationFailedExitCode;
    }
    return 0;
  };
}

const bool registered = register_command(
    {"verify", "Check an asset's Integral-Radiance tables against the fabric they came from",
     setup_verify});

}  // namespace
}  // namespace clothbake::cli

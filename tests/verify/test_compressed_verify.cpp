// verify_compressed (verify/compressed_verify.hpp) on a small baked-in-memory asset: the table
// errors it measures are the compression's, footprint classes and thresholds behave, the
// throughput comparison runs against raw tables built from the fabric, and bad inputs are named.
#include <gtest/gtest.h>

#include "bake/inputs/fabric_load.hpp"
#include "common/error.hpp"
#include "tables/radiance_fill.hpp"
#include "tests/support/compress_test_util.hpp"
#include "verify/compressed_verify.hpp"

namespace clothbake::compress {
namespace {

struct Baked {
  Fabric fabric;
  std::vector<uint8_t> labels;
  CompressionStats stats;
  std::unique_ptr<test::MemoryAsset> asset;
};

Baked bake(double target, bool with_labels = true) {
  Baked b;
  LoadOptions lo;
  lo.resolution = 32;
  b.fabric = load_fabric_description(
                 std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/twill.toml", lo)
                 .fabric;
  const auto& m = b.fabric.maps;
  for (std::size_t t = 0; t < m.texel_count(); ++t)
    b.labels.push_back(uint8_t(2 * (m.yarn_id[t] % 2) + (m.tangent[t][2] > 0 ? 1 : 0)));
  const auto in = tables::radiance_inputs(b.fabric, b.labels, 4);
  const DirectionalTexels data =
      directional_texels(reader::RadianceTableKind::Specular, in.view, 8);
  CpcaOptions o;
  o.rank = 32;
  o.target_error = target;
  auto sections = compressed_sections(compress_tables(data, o, &b.stats));
  if (with_labels)
    sections.push_back(formats::make_array_section<uint8_t>(reader::SectionType::ClusterLabels, 0,
                                                            b.labels, {32, 32}));
  b.asset = test::memory_asset(sections);
  return b;
}

TEST(CompressedVerify, MeasuresWhatTheCompressionStored) {
  const Baked b = bake(0.02);
  verify::CompressedVerifyOptions o;
  o.samples = 140;
  o.throughput_queries = 2000;
  o.max_footprint_error = 0.05;
  o.min_ratio = 2.0;
  const auto report = verify::verify_compressed(b.asset->asset, b.fabric, o);
  ASSERT_EQ(report.kinds.size(), 1u);
  const auto& k = report.kinds[0];
  EXPECT_EQ(k.kind, "specular");
  EXPECT_NEAR(k.tables.texel_rms_relative, b.stats.error, 1e-4);
  EXPECT_NEAR(k.bake_error, b.stats.error, 1e-12);
  EXPECT_GT(k.tables.tables, 0u);
  EXPECT_GT(k.tables.median_psnr_db, k.tables.min_psnr_db - 1e-9);
  EXPECT_NEAR(k.ratio, double(b.stats.raw_float_bytes) / double(k.compressed_bytes), 1e-9);
  EXPECT_GE(k.classes.size(), 4u);
  for (const auto& c : k.classes) {
    EXPECT_GT(c.footprints, 0) << c.size_class;
    EXPECT_TRUE(std::isfinite(c.rms_relative));
    EXPECT_LT(c.rms_relative, 0.1) << c.size_class;
  }
  EXPECT_TRUE(k.throughput_measured);
  EXPECT_FALSE(k.raw_from_asset);
  EXPECT_GT(k.compressed_queries_per_second, 0.0);
  EXPECT_GT(k.raw_queries_per_second, 0.0);
  EXPECT_TRUE(report.passed) << verify::compressed_report_text(report);
  const nlohmann::json j = verify::compressed_report_json(report);
  EXPECT_EQ(j["compressed"][0]["kind"], "specular");
  EXPECT_TRUE(j["passed"].get<bool>());
}

TEST(CompressedVerify, ThresholdsFailAndTheReliableSideMoves) {
  const Baked b = bake(0.1);  // coarse: large errors on small footprints
  verify::CompressedVerifyOptions o;
  o.samples = 140;
  o.throughput = false;
  o.max_footprint_error = 1e-6;  // nothing meets this
  o.min_ratio = 1e9;
  auto report = verify::verify_compressed(b.asset->asset, b.fabric, o);
  EXPECT_FALSE(report.passed);
  EXPECT_GE(report.failures.size(), 2u);
  EXPECT_FALSE(std::isfinite(report.kinds[0].min_reliable_side));
  o.max_footprint_error = 10.0;  // everything meets this
  o.min_ratio.reset();
  report = verify::verify_compressed(b.asset->asset, b.fabric, o);
  EXPECT_TRUE(report.passed);
  EXPECT_EQ(report.kinds[0].min_reliable_side, report.kinds[0].classes.front().min_side);
}

TEST(CompressedVerify, BadInputsAreNamed) {
  const Baked b = bake(0.05, /*with_labels=*/false);
  verify::CompressedVerifyOptions o;
  o.throughput = false;
  try {
    verify::verify_compressed(b.asset->asset, b.fabric, o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::InvalidAsset);
    EXPECT_NE(std::string(e.what()).find("label map"), std::string::npos);
  }
  const Baked good = bake(0.05);
  Fabric other = good.fabric;
  other.maps.resolution = 16;
  try {
    verify::verify_compressed(good.asset->asset, other, o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
  }
}

}  // namespace
}  // namespace clothbake::compress

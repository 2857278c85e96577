// verify/radiance_verify.hpp on assets built in memory: a faithful asset passes with SAT errors at
// the quantisation level in every size class; a tampered SAT, narrow lobes against coarse bins,
// and mismatched or incomplete assets are reported.
#include <gtest/gtest.h>

#include <cstring>

#include "common/error.hpp"
#include "formats/reader/asset.hpp"
#include "verify/radiance_verify.hpp"
#include "verify_fixtures.hpp"

using namespace clothbake;
using clothbake::verify_testing::asset_sections;
using clothbake::verify_testing::sat_section;

namespace {

struct Opened {
  std::vector<std::byte> bytes;
  reader::Asset asset;
};

std::unique_ptr<Opened> open(const std::vector<formats::Section>& sections) {
  auto o = std::make_unique<Opened>();
  o->bytes = formats::serialize_asset(sections);
  EXPECT_TRUE(o->asset.open_memory(o->bytes.data(), o->bytes.size()).ok());
  return o;
}

Fabric plain(int n, double roughness) {
  Fabric f = fabric_from_named_weave("plain", n).fabric;
  for (auto& y : f.yarns)
    y.roughness = roughness;
  return f;
}

tables::RadianceOptions small_bins(int bins) {
  tables::RadianceOptions o;
  o.bins_per_side = bins;
  o.warn_unresolved = false;
  return o;
}

}  // namespace

TEST(RadianceVerify, FaithfulAssetPassesInEverySizeClass) {
  const Fabric f = plain(32, 0.3);
  auto o = open(asset_sections(f, 3, small_bins(8)));
  verify::RadianceVerifyOptions options;
  options.samples = 70;
  const auto report = verify::verify_radiance(o->asset, f, options);
  EXPECT_TRUE(report.passed) << verify::report_text(report);
  ASSERT_GE(report.kinds.size(), 1u);
  const auto& spec = report.kinds[0];
  EXPECT_EQ(spec.kind, "specular");
  EXPECT_EQ(spec.resolution, 32);
  // Every size class of a 32^2 tile is sampled, from one texel to several tiles.
  std::vector<std::string> classes;
  for (const auto& s : spec.sat)
    classes.push_back(s.size_class);
  EXPECT_EQ(classes, (std::vector<std::string>{"1", "2", "4", "16", "tile", "tiles"}));
  EXPECT_LE(spec.sat_max, 1e-5);
  EXPECT_GT(spec.sat_max, 0.0);  // quantisation is visible, not hidden
  EXPECT_EQ(spec.directional.size(), spec.sat.size());
  // The plain weave has gaps: the gap table is verified too (no directional part).
  ASSERT_EQ(report.kinds.size(), 2u);
  EXPECT_EQ(report.kinds[1].kind, "gap");
  EXPECT_TRUE(report.kinds[1].directional.empty());
  EXPECT_LE(report.kinds[1].sat_max, 1e-5);
  const auto json = verify::report_json(report);
  EXPECT_EQ(json["passed"], true);
  EXPECT_EQ(json["tables"][0]["sat_error"][0]["size_class"], "1");
}

TEST(RadianceVerify, TamperedSatIsCaught) {
  const Fabric f = plain(32, 0.3);
  auto sections = asset_sections(f, 3, small_bins(8), [](std::vector<formats::Section>& s) {
    // Add 0.1 % of the tile total to every SAT element from texel (20, 20) on, in every bin and
    // column: one texel's value grows by that much (the SAT stays monotone, so only a comparison
    // with the fabric can tell).
    formats::Section* sat = sat_section(s, 0);
    const uint32_t bins = sat->dims[0], n = sat->dims[1], c = sat->dims[3];
    auto* v = reinterpret_cast<uint32_t*>(sat->payload.data());
    for (uint32_t b = 0; b < bins; ++b)
      for (uint32_t k = 0; k < c; ++k) {
        const uint32_t total = v[((std::size_t(b) * n + n - 1) * n + n - 1) * c + k];
        for (uint32_t y = 20; y < n; ++y)
          for (uint32_t x = 20; x < n; ++x)
            v[((std::size_t(b) * n + y) * n + x) * c + k] += total / 1000;
      }
  });
  auto o = open(sections);
  verify::RadianceVerifyOptions options;
  options.samples = 70;
  const auto report = verify::verify_radiance(o->asset, f, options);
  EXPECT_FALSE(report.passed);
  ASSERT_FALSE(report.failures.empty());
  EXPECT_NE(report.failures[0].find("specular tables: SAT error"), std::string::npos)
      << report.failures[0];
  EXPECT_GT(report.kinds[0].sat_max, 1e-3);
}

TEST(RadianceVerify, DirectionalErrorGrowsForNarrowLobesAndHasItsOwnThreshold) {
  verify::RadianceVerifyOptions options;
  options.samples = 42;
  const Fabric broad = plain(16, 0.5), narrow = plain(16, 0.02);
  auto ob = open(asset_sections(broad, 2, small_bins(16)));
  auto on = open(asset_sections(narrow, 2, small_bins(16)));
  const auto rb = verify::verify_radiance(ob->asset, broad, options);
  const auto rn = verify::verify_radiance(on->asset, narrow, options);
  EXPECT_TRUE(rb.passed);
  EXPECT_TRUE(rn.passed);                // no directional threshold: reported only
  EXPECT_LE(rn.kinds[0].sat_max, 1e-5);  // the tables are exact either way
  EXPECT_GT(rn.kinds[0].directional_max, 4 * rb.kinds[0].directional_max);
  EXPECT_EQ(rn.kinds[0].bins_needed, 63);  // ceil(sqrt(2 pi) / 0.04)
  options.max_dir_error = 2 * rb.kinds[0].directional_max;
  EXPECT_TRUE(verify::verify_radiance(ob->asset, broad, options).passed);
  const auto fail = verify::verify_radiance(on->asset, narrow, options);
  EXPECT_FALSE(fail.passed);
  ASSERT_FALSE(fail.failures.empty());
  EXPECT_NE(fail.failures[0].find("radiance_dirs >= 63"), std::string::npos) << fail.failures[0];
}

TEST(RadianceVerify, MismatchedOrIncompleteAssetsAreErrors) {
  const Fabric f = plain(16, 0.3);
  auto o = open(asset_sections(f, 2, small_bins(4)));
  verify::RadianceVerifyOptions options;
  options.samples = 14;
  try {
    verify::verify_radiance(o->asset, plain(32, 0.3), options);
    FAIL() << "resolution mismatch accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("32^2"), std::string::npos) << e.what();
  }
  // No tables at all.
  auto bare = asset_sections(f, 2, small_bins(4), [](std::vector<formats::Section>& s) {
    std::erase_if(s, [](const formats::Section& x) {
      return x.type == reader::SectionType::RadianceRawTables;
    });
  });
  auto ob = open(bare);
  try {
    verify::verify_radiance(ob->asset, f, options);
    FAIL() << "asset without tables accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::InvalidAsset);
  }
  // No label map.
  auto nolabels = asset_sections(f, 2, small_bins(4), [](std::vector<formats::Section>& s) {
    std::erase_if(
        s, [](const formats::Section& x) { return x.type == reader::SectionType::ClusterLabels; });
  });
  auto onl = open(nolabels);
  EXPECT_THROW(verify::verify_radiance(onl->asset, f, options), Error);
  // Bad options.
  options.samples = 0;
  EXPECT_THROW(verify::verify_radiance(o->asset, f, options), Error);
}

// verify/parallax_verify.hpp on assets built in memory: the compressed parallax against the raw
// table kept in the asset and against the one recomputed from the fabric (the same numbers, and
// the bake's own error), a planted code error found at its size, thresholds and a wrong fabric.
#include <gtest/gtest.h>

#include <cmath>

#include "bake/inputs/fabric_load.hpp"
#include "common/error.hpp"
#include "compress/parallax_codes.hpp"
#include "compress/parallax_hierarchy.hpp"
#include "formats/reader/asset.hpp"
#include "formats/writer/asset_writer.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"
#include "verify/parallax_verify.hpp"

using namespace clothbake;

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

struct Baked {
  Fabric fabric;
  raycast::ParallaxTable table;
  compress::HierarchicalParallax packed;
};

Baked bake(int n, int dirs) {
  Baked b;
  b.fabric = fabric_from_named_weave("twill2/1", n).fabric;
  raycast::ParallaxSettings s;
  s.dirs = dirs;
  b.table = raycast::bake_parallax(b.fabric.maps, s);
  const compress::ParallaxCodes raw{
      b.table.depth.data(),      b.table.resolution,  b.table.dirs,
      b.table.min_cos,           b.table.depth_scale, b.table.reference_height,
      b.table.stats.max_sideways};
  b.packed = compress::hierarchical_parallax(raw, compress::kDefaultParallaxMaxError);
  return b;
}

// The compressed sections, and with keep_raw the raw table `raw` (b.table by default).
std::vector<formats::Section> sections(const Baked& b, bool keep_raw,
                                       const raycast::ParallaxTable* raw = nullptr) {
  std::vector<formats::Section> out = compress::hierarchical_parallax_sections(b.packed);
  if (keep_raw)
    for (auto& s : raycast::parallax_sections(raycast::ParallaxTable(raw ? *raw : b.table)))
      out.push_back(std::move(s));
  return out;
}

}  // namespace

TEST(ParallaxVerify, MeasuresTheBakesErrorAgainstKeptOrRecomputedRaw) {
  const Baked b = bake(24, 4);
  ASSERT_GT(b.packed.rms_offset_error, 0.0);
  verify::ParallaxVerifyOptions options;
  options.samples = 70;
  for (bool keep : {true, false}) {
    auto o = open(sections(b, keep));
    const auto r = verify::verify_parallax(o->asset, b.fabric, options);
    EXPECT_EQ(r.raw_reference_from_asset, keep);
    EXPECT_TRUE(r.passed) << verify::parallax_report_text(r);
    EXPECT_EQ(r.entries, 24u * 24u * 16u);
    EXPECT_NEAR(r.rms_error, b.packed.rms_offset_error, 1e-12);
    EXPECT_NEAR(r.max_error, b.packed.max_offset_error, 1e-12);
    EXPECT_NEAR(r.share_above_quarter, b.packed.share_above_quarter, 1e-15);
    EXPECT_NEAR(r.max_depth_error, b.packed.max_depth_error, 1e-15);
    EXPECT_EQ(r.raw_bytes, 64u + 6u * r.entries);
    EXPECT_EQ(r.compressed_bytes, b.packed.payload_bytes());
    // Footprint means average the rounding errors away: every class is below the per-texel max.
    int sampled = 0;
    for (const auto& c : r.classes) {
      sampled += c.footprints;
      EXPECT_LE(c.rms_error, r.max_error + 1e-12) << c.size_class;
    }
    EXPECT_EQ(sampled, 70);
  }
}

TEST(ParallaxVerify, FindsAPlantedCodeErrorAtItsSize) {
  Baked b = bake(16, 4);
  // The direction with the largest offset per code; its texel (3, 5) of the kept raw table moved
  // by a quarter of the table's depth range (the compressed table then misses it by that much).
  const std::vector<double> k = compress::parallax_offset_per_depth(16, 4, b.packed.min_cos);
  std::size_t d = 0;
  for (std::size_t e = 0; e < k.size(); ++e)
    if (k[e] * b.packed.steps[e] > k[d] * b.packed.steps[d]) d = e;
  ASSERT_GT(b.packed.steps[d], 0.0);
  raycast::ParallaxTable planted_raw = b.table;
  const int raw_codes = 16384;
  uint16_t& code = planted_raw.depth[d * 256 + 5 * 16 + 3];
  code = uint16_t(code >= 32768 ? code - raw_codes : code + raw_codes);
  const double planted = raw_codes * b.table.depth_scale * k[d];
  auto o = open(sections(b, true, &planted_raw));
  verify::ParallaxVerifyOptions options;
  options.samples = 35;
  options.max_rms_error = 1.0;
  auto r = verify::verify_parallax(o->asset, b.fabric, options);
  // Within the texel's own rounding error (half a step) of the planted quarter range.
  EXPECT_NEAR(r.max_error, planted, 0.5 * b.packed.steps[d] * k[d] + 1e-12);
  EXPECT_GE(r.share_above_quarter, planted > 0.25 ? 1.0 / double(r.entries) : 0.0);
  EXPECT_TRUE(r.passed);
  // Thresholds below what was measured fail, each with its own message.
  options.max_error = r.max_error / 2;
  options.min_ratio = 1e6;
  r = verify::verify_parallax(o->asset, b.fabric, options);
  EXPECT_FALSE(r.passed);
  ASSERT_EQ(r.failures.size(), 2u);
  EXPECT_NE(r.failures[0].find("per-texel maximum offset error"), std::string::npos);
  EXPECT_NE(r.failures[1].find("size ratio"), std::string::npos);
}

TEST(ParallaxVerify, RefusesAFabricOfAnotherResolution) {
  const Baked b = bake(16, 2);
  auto o = open(sections(b, false));
  const Fabric other = fabric_from_named_weave("twill2/1", 24).fabric;
  try {
    verify::verify_parallax(o->asset, other, {});
    FAIL() << "expected an input error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("resolution"), std::string::npos) << e.what();
  }
  // Without a compressed table there is nothing to verify: an invalid asset.
  auto raw_only = open(raycast::parallax_sections(raycast::ParallaxTable(b.table)));
  EXPECT_FALSE(verify::has_compressed_parallax(raw_only->asset));
  EXPECT_THROW(verify::verify_parallax(raw_only->asset, b.fabric, {}), Error);
}

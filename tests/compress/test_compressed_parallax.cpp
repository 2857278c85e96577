// The compressed parallax form (compress/parallax_codes.hpp, format 1.1) through the writer and
// the reader: decoded values against the raw table on woven, tall, spiky and flat height fields
// (flat must stay exactly 0), the bound the record states, footprint means against direct means
// of the decoded per-texel values (the on-demand SATs are exact), the same API as the raw form,
// hostile sections (stable IDs from open() and validate), and the format minor the writer stamps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <string>

#include "common/error.hpp"
#include "compress/parallax_codes.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"
#include "tests/compress/parallax_test_util.hpp"
#include "tests/raycast/synthetic_fields.hpp"
#include "tests/support/memory_asset.hpp"

using namespace clothbake;
using namespace clothbake::raycast;
using reader::ErrorCode;

namespace {

using compress::test::baked;
using compress::test::spiky_maps;
using test_support::MemoryAsset;

compress::ParallaxCodes codes_of(const ParallaxTable& t) {
  return {t.depth.data(),     t.resolution,        t.dirs, t.min_cos, t.depth_scale,
          t.reference_height, t.stats.max_sideways};
}

// Compressed and raw sections of one table, with metadata.
std::vector<formats::Section> both_forms(const ParallaxTable& table,
                                         compress::QuantisedParallax* packed_out = nullptr) {
  compress::QuantisedParallax packed = compress::quantise_parallax(codes_of(table));
  std::vector<formats::Section> s = compress::compressed_parallax_sections(packed);
  ParallaxTable copy = table;
  for (auto& x : parallax_sections(std::move(copy)))
    s.push_back(std::move(x));
  s.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  if (packed_out) *packed_out = std::move(packed);
  return s;
}

// Decoded values against raw: every texel and bin within the recorded max depth error, which is
// at most half the direction's step; the recorded errors are the ones measured here.
void expect_close_to_raw(const ParallaxTable& table, const char* what) {
  compress::QuantisedParallax packed;
  MemoryAsset m(both_forms(table, &packed));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  reader::ParallaxView raw, view;
  ASSERT_TRUE(raw.open(m.asset, reader::ParallaxSource::Raw).ok());
  ASSERT_TRUE(view.open(m.asset, reader::ParallaxSource::Compressed).ok());
  EXPECT_TRUE(view.is_compressed());
  EXPECT_TRUE(view.has_sat());
  const int n = table.resolution, d = table.dirs * table.dirs;
  const std::vector<double> per_depth =
      compress::parallax_offset_per_depth(n, table.dirs, table.min_cos);
  double worst = 0, sum2 = 0;
  for (int bin = 0; bin < d; ++bin) {
    const double half_step = view.depth_step(uint32_t(bin)) / 2;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double e = std::fabs(view.bin_depth(uint32_t(bin), x, y) - table.r(bin, x, y));
        ASSERT_LE(e, half_step * (1 + 1e-9) + 1e-18) << what << " bin " << bin;
        worst = std::max(worst, e);
        sum2 += (e * per_depth[std::size_t(bin)]) * (e * per_depth[std::size_t(bin)]);
      }
  }
  EXPECT_EQ(view.compressed_info().max_depth_error, worst) << what;
  EXPECT_NEAR(view.compressed_info().rms_offset_error, std::sqrt(sum2 / (double(d) * n * n)), 1e-12)
      << what;
  // The same API: per-texel queries (wrapping) agree with the raw form within the error.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    const double v[3] = {u(rng), u(rng), std::fabs(u(rng)) + 0.05};
    const int64_t x = int64_t(rng() % 64) - 32, y = int64_t(rng() % 64) - 32;
    reader::ParallaxSample a, b;
    ASSERT_TRUE(raw.depth(x, y, v, &a).ok());
    ASSERT_TRUE(view.depth(x, y, v, &b).ok());
    EXPECT_LE(std::fabs(a.r - b.r), worst * (1 + 1e-9) + 1e-18) << what;
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(a.direction[k], b.direction[k]);
  }
  // The validator accepts it and cross-checks it against the raw table.
  struct Sink {
    std::set<std::string> ids;
  } sink;
  const auto summary = reader::validate_asset(
      m.asset,
      [](void* u, reader::Check c, uint32_t, const char*) {
        static_cast<Sink*>(u)->ids.insert(reader::check_id(c));
      },
      &sink);
  EXPECT_EQ(summary.errors, 0u) << what << ": " << (sink.ids.empty() ? "" : *sink.ids.begin());
}

}  // namespace

TEST(CompressedParallax, DecodesWithinTheRecordedErrorOnWovenTallAndSpikyFields) {
  expect_close_to_raw(baked(rctest::plain_weave_maps(16)), "plain weave");
  expect_close_to_raw(baked(rctest::plain_weave_maps(16, 2, 0.4, 0.1)), "tall yarns");
  expect_close_to_raw(baked(spiky_maps()), "spikes");
}

TEST(CompressedParallax, FlatMapStaysExactlyZero) {
  const ParallaxTable table = baked(rctest::maps_from(8, [](double, double) { return 0.25; }));
  compress::QuantisedParallax packed;
  MemoryAsset m(both_forms(table, &packed));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset, reader::ParallaxSource::Compressed).ok());
  for (uint32_t bin = 0; bin < 64; ++bin) {
    EXPECT_EQ(view.depth_step(bin), 0.0);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        ASSERT_EQ(view.bin_depth(bin, x, y), 0.0);
  }
  reader::ParallaxSample s;
  const double v[3] = {0.5, 0.1, 0.7};
  ASSERT_TRUE(view.footprint_depth({-3.5, 2, 20, 9.25}, v, &s).ok());
  EXPECT_EQ(s.r, 0.0);
  EXPECT_EQ(s.offset[0], 0.0);
  EXPECT_EQ(packed.rms_offset_error, 0.0);
}

TEST(CompressedParallax, FootprintMeansAreExactMeansOfTheDecodedTexels) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16), 6);
  MemoryAsset m(both_forms(table));
  reader::ParallaxView view, raw;
  ASSERT_TRUE(view.open(m.asset, reader::ParallaxSource::Compressed).ok());
  ASSERT_TRUE(raw.open(m.asset, reader::ParallaxSource::Raw).ok());
  const int n = 16;
  const model::DirectionGrid<double> grid{6, table.min_cos};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> pos(-40, 40), ext(0, 40), u(-1, 1);
  for (int i = 0; i < 300; ++i) {
    const double x0 = pos(rng), y0 = pos(rng);
    const double x1 = x0 + (i % 3 == 0 ? std::floor(ext(rng)) : ext(rng)), y1 = y0 + ext(rng);
    if (!((x1 - x0) * (y1 - y0) > 0)) continue;
    double view_dir[3] = {u(rng), u(rng), 0.6 + std::fabs(u(rng))};
    reader::ParallaxSample s, r;
    ASSERT_TRUE(view.footprint_depth({x0, y0, x1, y1}, view_dir, &s).ok());
    ASSERT_TRUE(raw.footprint_depth({x0, y0, x1, y1}, view_dir, &r).ok());
    // Direct: the area-weighted mean of the decoded per-texel values over the covered texels.
    const model::BinBilinear<double> w =
        grid.bilinear_fast(model::Vec3d(s.direction[0], s.direction[1], s.direction[2]));
    double sum = 0;
    for (long ty = long(std::floor(y0)); ty < long(std::ceil(y1)); ++ty) {
      const double hy = std::min(y1, double(ty + 1)) - std::max(y0, double(ty));
      for (long tx = long(std::floor(x0)); tx < long(std::ceil(x1)); ++tx) {
        const double hx = std::min(x1, double(tx + 1)) - std::max(x0, double(tx));
        double texel = 0;
        for (int k = 0; k < 4; ++k)
          if (w.weight[k] > 0) texel += w.weight[k] * view.bin_depth(uint32_t(w.index[k]), tx, ty);
        sum += hx * hy * texel;
      }
    }
    const double direct = sum / ((x1 - x0) * (y1 - y0));
    ASSERT_NEAR(s.r, direct, 1e-12 * (std::fabs(direct) + 1e-6)) << i;
    // And within the per-texel bound of the raw footprint mean.
    EXPECT_LE(std::fabs(s.r - r.r), view.compressed_info().max_depth_error * (1 + 1e-9) + 1e-15);
  }
  EXPECT_GT(view.decoded_bytes(), 0u);
  EXPECT_LE(view.decoded_bytes(), uint64_t(36) * n * n * 4);  // only the directions touched
  // weighted_depth (the evaluator's hot path) is depth() with the bins computed once.
  const double v[3] = {0.2, -0.4, 0.8};
  double o[3];
  ASSERT_TRUE(view.view_direction(v, o).ok());
  const model::BinBilinear<double> w = grid.bilinear_fast(model::Vec3d(o[0], o[1], o[2]));
  reader::ParallaxSample s;
  ASSERT_TRUE(view.depth(-3, 21, v, &s).ok());
  EXPECT_NEAR(view.weighted_depth(w.index, w.weight, -3, 21), s.r, 1e-15);
}

TEST(CompressedParallax, HostileSectionsFailWithStableIds) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(8), 4);
  compress::QuantisedParallax packed = compress::quantise_parallax(codes_of(table));
  auto base = compress::compressed_parallax_sections(packed);
  base.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  auto open_with = [](const std::vector<formats::Section>& s, std::string* ids) {
    MemoryAsset m(s);
    EXPECT_TRUE(m.status.ok()) << m.status.message();
    reader::ParallaxView view;
    const reader::Status st = view.open(m.asset);
    struct Sink {
      std::string ids;
    } sink;
    reader::validate_asset(
        m.asset,
        [](void* u, reader::Check c, uint32_t, const char*) {
          static_cast<Sink*>(u)->ids += std::string(reader::check_id(c)) + " ";
        },
        &sink);
    *ids = sink.ids;
    return st;
  };
  auto info_of = [](formats::Section& s) {
    return reinterpret_cast<reader::CompressedParallaxInfoRecord*>(s.payload.data());
  };
  std::string ids;
  {
    ASSERT_TRUE(open_with(base, &ids).ok());
    EXPECT_EQ(ids, "");
  }
  {  // unknown bit depth
    auto s = base;
    info_of(s[0])->bits = 7;
    const auto st = open_with(s, &ids);
    EXPECT_EQ(st.code(), ErrorCode::Unsupported);
    EXPECT_EQ(std::string(reader::check_id(st.check())), "CBK-E015");
    EXPECT_NE(ids.find("CBK-E015"), std::string::npos) << ids;
  }
  {  // resolution disagreeing with the codes' shape
    auto s = base;
    info_of(s[0])->resolution = 9;
    const auto st = open_with(s, &ids);
    EXPECT_EQ(std::string(reader::check_id(st.check())), "CBK-E015");
    EXPECT_NE(ids.find("CBK-E015"), std::string::npos) << ids;
  }
  {  // a negative step and one above a tile (NaN fails the same test; the writer refuses NaN)
    for (double bad : {-1e-3, 2.0}) {
      auto s = base;
      std::vector<double> steps(16);
      std::memcpy(steps.data(), s[1].payload.data(), 16 * 8);
      steps[5] = bad;
      s[1] = formats::make_array_section<double>(s[1].type, s[1].instance, steps, {16});
      const auto st = open_with(s, &ids);
      EXPECT_EQ(std::string(reader::check_id(st.check())), "CBK-E021") << bad;
      EXPECT_NE(ids.find("CBK-E021"), std::string::npos) << ids;
    }
  }
  {  // codes missing
    auto s = base;
    s.erase(s.begin() + 2);
    const auto st = open_with(s, &ids);
    EXPECT_EQ(st.code(), ErrorCode::NotFound);
    EXPECT_NE(ids.find("CBK-E019"), std::string::npos) << ids;
  }
  {  // codes as u16
    auto s = base;
    s[2] = formats::make_array_section<uint16_t>(s[2].type, s[2].instance,
                                                 std::vector<uint16_t>(16 * 8 * 8, 1), {16, 8, 8});
    const auto st = open_with(s, &ids);
    EXPECT_EQ(std::string(reader::check_id(st.check())), "CBK-E015");
  }
  {  // a non-zero code in a direction whose step is 0
    auto s = base;
    std::vector<double> steps(16);
    std::memcpy(steps.data(), s[1].payload.data(), 16 * 8);
    steps[3] = 0.0;
    s[1] = formats::make_array_section<double>(s[1].type, s[1].instance, steps, {16});
    s[2].payload[3 * 64 + 5] = std::byte{9};
    const auto st = open_with(s, &ids);
    EXPECT_TRUE(st.ok());
    EXPECT_NE(ids.find("CBK-E021"), std::string::npos) << ids;
  }
  {  // beside a raw table it disagrees with
    auto s = base;
    ParallaxTable copy = table;
    for (auto& x : parallax_sections(std::move(copy)))
      s.push_back(std::move(x));
    s[2].payload[7] ^= std::byte{0x40};
    const auto st = open_with(s, &ids);
    EXPECT_TRUE(st.ok());
    EXPECT_NE(ids.find("CBK-E022"), std::string::npos) << ids;
  }
}

TEST(CompressedParallax, SixteenBitFormWhenEightBitsMissTheTarget) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16, 2, 0.4, 0.1));
  const compress::QuantisedParallax eight = compress::quantise_parallax(codes_of(table), 1.0);
  ASSERT_EQ(eight.bits, 8);
  ASSERT_GT(eight.rms_offset_error, 0.0);
  // A target below what 8 bits reach: the raw codes, exactly, as 16-bit compressed codes.
  const compress::QuantisedParallax p =
      compress::quantise_parallax(codes_of(table), eight.rms_offset_error / 2);
  EXPECT_EQ(p.bits, 16);
  EXPECT_EQ(p.rms_offset_error_8bit, eight.rms_offset_error);
  auto s = compress::compressed_parallax_sections(p);
  ParallaxTable copy = table;
  for (auto& x : parallax_sections(std::move(copy)))
    s.push_back(std::move(x));
  s.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  MemoryAsset m(s);
  reader::ParallaxView view, raw;
  ASSERT_TRUE(view.open(m.asset, reader::ParallaxSource::Compressed).ok());
  ASSERT_TRUE(raw.open(m.asset, reader::ParallaxSource::Raw).ok());
  EXPECT_EQ(view.compressed_info().bits, 16u);
  for (uint32_t bin = 0; bin < 64; ++bin)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x)
        ASSERT_EQ(view.bin_depth(bin, x, y), table.r(int(bin), x, y));
  const double v[3] = {0.4, 0.3, 0.7};
  reader::ParallaxSample a, b;
  ASSERT_TRUE(view.footprint_depth({-5.25, 3, 30, 17.5}, v, &a).ok());
  ASSERT_TRUE(raw.footprint_depth({-5.25, 3, 30, 17.5}, v, &b).ok());
  EXPECT_NEAR(a.r, b.r, 1e-15);
  struct Sink {
    int errors = 0;
  } sink;
  reader::validate_asset(
      m.asset,
      [](void* u, reader::Check, uint32_t, const char*) { ++static_cast<Sink*>(u)->errors; },
      &sink);
  EXPECT_EQ(sink.errors, 0);
  EXPECT_THROW(compress::quantise_parallax(codes_of(table), 0.0), Error);
}

TEST(CompressedParallax, WriterStampsTheMinorTheSectionsNeed) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(8), 4);
  MemoryAsset with(both_forms(table));
  EXPECT_EQ(with.asset.version_minor(), 1);
  ParallaxTable copy = table;
  auto raw_only = parallax_sections(std::move(copy));
  raw_only.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  MemoryAsset without(raw_only);
  EXPECT_EQ(without.asset.version_minor(), 0);  // a 1.0 file, byte for byte as before
  // Auto prefers the exact raw table when both are present.
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(with.asset).ok());
  EXPECT_FALSE(view.is_compressed());
}

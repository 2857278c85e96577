// The compressed parallax (the hierarchical form: compress/parallax_hierarchy.hpp writes it,
// formats/reader/parallax_hierarchy.hpp decodes it) through the writer and the reader: every
// direction decodes to exactly the encoder's codes on woven, tall, spiky and flat fields and on
// grids of every size class (references at the grid's edges), the measured error meets the
// target and the queries agree with the raw table within it, footprint means are exact means of
// the decoded texels (the on-demand SATs), the reference structure has at most
// two levels, the output is byte-identical for any thread count, and hostile blocks and sections
// fail with stable IDs without reading out of bounds.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "common/error.hpp"
#include "compress/parallax_codes.hpp"
#include "compress/parallax_entropy.hpp"
#include "compress/parallax_hierarchy.hpp"
#include "formats/reader/parallax_hierarchy.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"
#include "tests/compress/corrupt_blocks.hpp"
#include "tests/compress/parallax_test_util.hpp"
#include "tests/raycast/synthetic_fields.hpp"
#include "tests/support/memory_asset.hpp"

using namespace clothbake;
using namespace clothbake::raycast;
using reader::ErrorCode;
using reader::SectionType;

namespace {

using compress::test::baked;
using compress::test::spiky_maps;
using test_support::MemoryAsset;
using test_support::validate_ids;
using test_support::with_metadata;

compress::ParallaxCodes raw_of(const ParallaxTable& t) {
  return {t.depth.data(),     t.resolution,        t.dirs, t.min_cos, t.depth_scale,
          t.reference_height, t.stats.max_sideways};
}

// Encodes `table`, opens it, and checks every code, the error target and the queries against the
// raw table.
void expect_round_trip(const ParallaxTable& table, const char* what, double max_error = 0.05) {
  const compress::HierarchicalParallax p =
      compress::hierarchical_parallax(raw_of(table), max_error);
  EXPECT_LE(p.rms_offset_error, max_error) << what;
  MemoryAsset m(with_metadata(compress::hierarchical_parallax_sections(p)));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  EXPECT_EQ(m.asset.version_major(), 2) << what;
  EXPECT_EQ(m.asset.version_minor(), 0) << what;
  reader::ParallaxView view;
  const reader::Status opened = view.open(m.asset);
  ASSERT_TRUE(opened.ok()) << what << ": " << opened.message();
  EXPECT_TRUE(view.is_compressed());
  EXPECT_EQ(view.decoded_bytes(), 0u) << "nothing decoded at open";
  EXPECT_TRUE(view.decode_all().ok()) << what;
  const uint32_t n = view.resolution(), d = view.dirs() * view.dirs();
  // Directions in a scattered order, so that a plane is decoded before and after its references.
  for (uint32_t k = 0; k < d; ++k) {
    const uint32_t bin = (k * 7919u) % d;
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x)
        ASSERT_EQ(view.bin_code(bin, x, y), p.codes[(uint64_t(bin) * n + y) * n + x])
            << what << " bin " << bin << " texel " << x << ", " << y;
    EXPECT_EQ(view.depth_step(bin), p.steps[bin]);
  }
  // The raw view answers the same queries within the error the codes allow.
  MemoryAsset raw(with_metadata(parallax_sections(ParallaxTable(table))));
  reader::ParallaxView exact;
  ASSERT_TRUE(exact.open(raw.asset).ok());
  const double views[3][3] = {{0.2, -0.4, 0.8}, {-0.7, 0.1, 0.3}, {0, 0, 1}};
  double max_step = 0;
  for (uint32_t bin = 0; bin < d; ++bin)
    max_step = std::max(max_step, p.steps[bin]);
  for (const auto& v : views) {
    reader::ParallaxSample a, b;
    ASSERT_TRUE(view.depth(-3, 21, v, &a).ok());
    ASSERT_TRUE(exact.depth(-3, 21, v, &b).ok());
    EXPECT_NEAR(a.r, b.r, max_step / 2 + table.depth_scale) << what;
    ASSERT_TRUE(view.footprint_depth({-5.25, 3, 30, 17.5}, v, &a).ok());
    ASSERT_TRUE(exact.footprint_depth({-5.25, 3, 30, 17.5}, v, &b).ok());
    EXPECT_NEAR(a.r, b.r, max_step / 2 + table.depth_scale) << what;
  }
  EXPECT_EQ(validate_ids(m.asset), "") << what;
}

}  // namespace

TEST(HierarchicalParallax, ReferencesHaveAtMostTwoLevelsAndStayInTheGrid) {
  for (uint32_t n : {1u, 2u, 3u, 5u, 6u, 8u, 9u, 32u}) {
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) {
        const reader::ParallaxReferences r = reader::parallax_references(i, j, n);
        const bool key = i % 4 == 0 && j % 4 == 0;
        EXPECT_EQ(r.level == 0, key);
        EXPECT_EQ(r.count == 0, key) << "every other bin has a reference";
        for (int e = 0; e < r.count; ++e) {
          ASSERT_LT(r.bin[e], n * n);
          const reader::ParallaxReferences rr =
              reader::parallax_references(r.bin[e] % n, r.bin[e] / n, n);
          EXPECT_LT(rr.level, r.level) << "references are of a lower level";
          const int64_t di = int64_t(r.bin[e] % n) - i, dj = int64_t(r.bin[e] / n) - j;
          EXPECT_LE(std::max(std::abs(di), std::abs(dj)), r.level == 1 ? 2 : 1);
        }
      }
  }
}

TEST(HierarchicalParallax, DecodesToTheEncodersCodesOnWovenTallSpikyAndFlatFields) {
  expect_round_trip(baked(rctest::plain_weave_maps(16)), "plain weave");
  expect_round_trip(baked(rctest::plain_weave_maps(24, 2, 0.4, 0.1), 6), "tall yarns");
  expect_round_trip(baked(rctest::plain_weave_maps(12, 3, 3.0, 1.0), 5), "very tall yarns");
  expect_round_trip(baked(spiky_maps()), "spikes");
  for (int dirs : {1, 2, 3, 4, 7, 9})
    expect_round_trip(baked(rctest::plain_weave_maps(8), dirs),
                      ("grid " + std::to_string(dirs)).c_str());
  expect_round_trip(baked(rctest::plain_weave_maps(16)), "tight target", 0.002);
  // Flat: every step 0 and every code 0, decoded as exactly r = 0.
  const ParallaxTable flat = baked(rctest::maps_from(8, [](double, double) { return 0.25; }));
  expect_round_trip(flat, "flat");
  MemoryAsset m(with_metadata(
      compress::hierarchical_parallax_sections(compress::hierarchical_parallax(raw_of(flat)))));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  reader::ParallaxSample s;
  const double v[3] = {0.5, 0.1, 0.7};
  ASSERT_TRUE(view.footprint_depth({-3.5, 2, 20, 9.25}, v, &s).ok());
  EXPECT_EQ(s.r, 0.0);
  ASSERT_TRUE(view.depth(3, -2, v, &s).ok());
  EXPECT_EQ(s.r, 0.0);
}

TEST(HierarchicalParallax, FootprintMeansAreExactMeansOfTheDecodedTexels) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16), 6);
  const compress::HierarchicalParallax p = compress::hierarchical_parallax(raw_of(table), 0.05);
  std::vector<formats::Section> sections = compress::hierarchical_parallax_sections(p);
  for (auto& s : parallax_sections(ParallaxTable(table)))
    sections.push_back(std::move(s));
  MemoryAsset m(with_metadata(std::move(sections)));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  reader::ParallaxView view, raw;
  ASSERT_TRUE(view.open(m.asset, reader::ParallaxSource::Compressed).ok());
  ASSERT_TRUE(raw.open(m.asset, reader::ParallaxSource::Raw).ok());
  EXPECT_TRUE(view.has_sat());
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
  // Only the directions touched, each at most a u16 plane and a u32 SAT.
  EXPECT_LE(view.decoded_bytes(), uint64_t(36) * n * n * 6);
  // weighted_depth (the evaluator's hot path) is depth() with the bins computed once.
  const double v[3] = {0.2, -0.4, 0.8};
  double o[3];
  ASSERT_TRUE(view.view_direction(v, o).ok());
  const model::BinBilinear<double> w = grid.bilinear_fast(model::Vec3d(o[0], o[1], o[2]));
  reader::ParallaxSample s;
  ASSERT_TRUE(view.depth(-3, 21, v, &s).ok());
  EXPECT_NEAR(view.weighted_depth(w.index, w.weight, -3, 21), s.r, 1e-15);
}

TEST(HierarchicalParallax, UsesTheTilesRepeatAndIsByteIdenticalForAnyThreadCount) {
  // A plain weave of 4 threads on 32^2 repeats after (16, 16).
  const ParallaxTable table = baked(rctest::plain_weave_maps(32, 4), 8);
  const compress::HierarchicalParallax p = compress::hierarchical_parallax(raw_of(table));
  ASSERT_FALSE(p.candidates.empty());
  EXPECT_GT(p.shifted_blocks, 0u);
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const compress::HierarchicalParallax again = compress::hierarchical_parallax(raw_of(table));
  EXPECT_EQ(again.codes, p.codes);
  EXPECT_EQ(again.stream, p.stream);
  EXPECT_EQ(again.offsets, p.offsets);
  EXPECT_EQ(again.tables, p.tables);
  EXPECT_EQ(again.weights, p.weights);
}

// The planned form: a keep mask closed under the references stores those directions with exactly
// the full table's codes (steps depend on the grid and the relief, not on which rays were cast),
// left-out directions are empty blocks answering OutOfPlan, and a mask that leaves out a
// reference, or blocks that disagree with the mask, are refused.
TEST(HierarchicalParallax, APlannedTableStoresItsDirectionsWithTheFullCodes) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16), 8);
  const uint32_t dirs = 8, bins = dirs * dirs, n = 16;
  std::vector<uint8_t> views(bins, 0);
  for (uint32_t j = 3; j < 6; ++j)
    for (uint32_t i = 5; i < 8; ++i)
      views[j * dirs + i] = 1;
  std::vector<uint8_t> keep = views;
  reader::close_under_parallax_references(keep.data(), dirs);
  EXPECT_GT(compress::kept_direction_count(keep), compress::kept_direction_count(views));
  EXPECT_THROW(compress::hierarchical_parallax(raw_of(table), 0.05, views), Error)
      << "a mask without the references is refused";
  // A planned bake casts only the kept directions: the others are zeros in its raw table.
  ParallaxTable cast = table;
  for (uint32_t b = 0; b < bins; ++b)
    if (!keep[b]) std::fill_n(cast.depth.begin() + std::ptrdiff_t(b) * n * n, n * n, uint16_t(0));
  const compress::HierarchicalParallax full = compress::hierarchical_parallax(raw_of(table));
  const compress::HierarchicalParallax planned =
      compress::hierarchical_parallax(raw_of(cast), 0.05, keep);
  EXPECT_TRUE(planned.planned);
  EXPECT_LT(planned.stream.size(), full.stream.size());
  auto sections = compress::hierarchical_parallax_sections(planned);
  sections.push_back(formats::make_array_section<uint8_t>(SectionType::BinMap, reader::kViewBinMap,
                                                          keep, {dirs, dirs}));
  MemoryAsset m(with_metadata(sections));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  reader::ParallaxView view;
  const reader::Status opened = view.open(m.asset);
  ASSERT_TRUE(opened.ok()) << opened.message();
  EXPECT_TRUE(view.is_planned());
  EXPECT_TRUE(view.decode_all().ok());
  EXPECT_EQ(validate_ids(m.asset), "");
  for (uint32_t b = 0; b < bins; ++b) {
    ASSERT_EQ(view.covers(b), keep[b] != 0) << b;
    if (!keep[b]) {
      EXPECT_FALSE(view.ensure_plane(b));
      EXPECT_EQ(view.bin_codes(b), nullptr);
      continue;
    }
    EXPECT_EQ(view.depth_step(b), full.steps[b]);
    const uint16_t* plane = view.bin_codes(b);
    ASSERT_NE(plane, nullptr);
    for (uint32_t t = 0; t < n * n; ++t) {
      ASSERT_EQ(view.bin_code(b, t % n, t / n), full.codes[uint64_t(b) * n * n + t]) << b;
      ASSERT_EQ(plane[t], full.codes[uint64_t(b) * n * n + t]) << b;
    }
  }
  // A view whose bilinear bins are all kept answers; one that needs a left-out bin does not.
  const model::DirectionGrid<double> grid{int(dirs), table.min_cos};
  const model::Vec3d kept_view = grid.bin_center(6, 4), left_view = grid.bin_center(1, 1);
  reader::ParallaxSample s;
  const double kv[3] = {kept_view.x, kept_view.y, kept_view.z};
  const double lv[3] = {left_view.x, left_view.y, left_view.z};
  EXPECT_TRUE(view.depth(2, 3, kv, &s).ok());
  EXPECT_EQ(view.depth(2, 3, lv, &s).code(), ErrorCode::OutOfPlan);
  EXPECT_EQ(view.footprint_depth({0, 0, 9, 9}, lv, &s).code(), ErrorCode::OutOfPlan);
  // The bin map must hold the references of every stored direction, and match the blocks.
  for (const auto& [map, what] :
       std::vector<std::pair<std::vector<uint8_t>, const char*>>{{views, "map without refs"}}) {
    auto bad = compress::hierarchical_parallax_sections(planned);
    bad.push_back(formats::make_array_section<uint8_t>(SectionType::BinMap, reader::kViewBinMap,
                                                       map, {dirs, dirs}));
    MemoryAsset b(with_metadata(bad));
    reader::ParallaxView v;
    const reader::Status st = v.open(b.asset);
    EXPECT_EQ(std::string(reader::check_id(st.check())), "CBK-E021") << what << st.message();
  }
}

TEST(HierarchicalParallax, EveryCorruptionOrTruncationOfABlockIsSafe) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16), 4);
  const compress::HierarchicalParallax p = compress::hierarchical_parallax(raw_of(table));
  const uint32_t n = 16, dirs = 4;
  // Bin (1, 0): level 2, references (0, 0) and (2, 0).
  const uint32_t bin = 1;
  const reader::ParallaxReferences refs = reader::parallax_references(1, 0, dirs);
  ASSERT_EQ(refs.count, 2);
  const uint16_t* ref_planes[4];
  uint32_t ref_m[4];
  for (int e = 0; e < refs.count; ++e) {
    ref_planes[e] = p.codes.data() + uint64_t(refs.bin[e]) * n * n;
    ref_m[e] = p.weights[refs.bin[e]];
  }
  const uint16_t* tables = p.tables.data();
  const std::vector<uint8_t> block(p.stream.begin() + std::ptrdiff_t(p.offsets[bin]),
                                   p.stream.begin() + std::ptrdiff_t(p.offsets[bin + 1]));
  auto decode = [&](const std::vector<uint8_t>& b, std::vector<uint16_t>& plane) {
    static reader::ParallaxHierScratch scratch;
    std::vector<int32_t> diff(n * n);
    return reader::decode_hierarchical_block(b.data(), b.size(), tables, p.groups, n,
                                             p.weights[bin], ref_planes, ref_m, refs.count,
                                             plane.data(), diff.data(), &scratch);
  };
  std::vector<uint16_t> plane(n * n);
  ASSERT_TRUE(decode(block, plane).ok());
  EXPECT_TRUE(
      std::equal(plane.begin(), plane.end(), p.codes.begin() + std::ptrdiff_t(bin) * n * n));
  // A block that does not decode leaves a zero plane (the reader's contract).
  compress_test::expect_corruptions_detected(
      block, [&](const std::vector<uint8_t>& b) { return decode(b, plane); },
      [&](std::size_t len) {
        EXPECT_TRUE(std::all_of(plane.begin(), plane.end(), [](uint16_t c) { return c == 0; }))
            << len;
      });
}

TEST(HierarchicalParallax, HostileSectionsFailWithStableIds) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(8), 4);
  const compress::HierarchicalParallax p = compress::hierarchical_parallax(raw_of(table));
  const auto base = with_metadata(compress::hierarchical_parallax_sections(p));
  if (const char* dir = std::getenv("CLOTHBAKE_SAVE_CRAFTED")) {
    // How tests/fuzz/corpus/parallax_hierarchy.cbk was made: this 8^2 table of 4^2 directions.
    const auto bytes = formats::serialize_asset(base);
    std::ofstream(std::string(dir) + "/parallax_hierarchy.cbk", std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  const auto find = compress::test::parallax_entropy_section;
  const auto check = compress::test::expect_hostile_parallax;
  {
    MemoryAsset m(base);
    EXPECT_EQ(validate_ids(m.asset), "");
  }
  {  // bits other than 16
    auto s = base;
    reinterpret_cast<reader::CompressedParallaxInfoRecord*>(find(s, 0).payload.data())->bits = 8;
    check(s, "CBK-E015", "CBK-E015");
  }
  {  // one instance at payload version 2 among version 1 (format 1.5's numbering)
    auto s = base;
    find(s, 5).version = 2;
    check(s, "CBK-E015", "CBK-E015");
  }
  {  // a prediction weight of 0, and one beyond 2^24
    for (uint32_t w : {0u, (1u << 24) + 1}) {
      auto s = base;
      reinterpret_cast<uint32_t*>(find(s, 5).payload.data())[3] = w;
      check(s, "CBK-E021", "CBK-E021");
    }
  }
  {  // the weights missing
    auto s = base;
    s.erase(std::find_if(s.begin(), s.end(), [](const formats::Section& x) {
      return x.type == SectionType::ParallaxEntropy && x.instance == 5;
    }));
    check(s, "CBK-E019", "CBK-E019");
  }
  {  // offsets that decrease, and an empty block in a full table
    auto s = base;
    auto* v = reinterpret_cast<uint64_t*>(find(s, 2).payload.data());
    v[3] = v[5] + 1;
    check(s, "CBK-E021", "CBK-E021");
    s = base;
    v = reinterpret_cast<uint64_t*>(find(s, 2).payload.data());
    v[2] = v[1];
    check(s, "CBK-E021", "CBK-E021");
  }
  {  // frequency tables that do not sum to 4096; tables of the 8-bit form's shape
    auto s = base;
    auto* t = reinterpret_cast<uint16_t*>(find(s, 4).payload.data());
    t[0] = uint16_t(t[0] + 1);
    check(s, "CBK-E021", "CBK-E021");
    s = base;
    find(s, 4) = formats::make_array_section<uint16_t>(SectionType::ParallaxEntropy, 4,
                                                       std::vector<uint16_t>(5 * 256, 0),
                                                       {1, 5, 256}, reader::kHierParallaxVersion);
    check(s, "CBK-E015", "CBK-E015");
  }
  {  // the planned flag without bin_map instance 1 (its stored directions), and an unknown flag
    auto s = base;
    reinterpret_cast<reader::CompressedParallaxInfoRecord*>(find(s, 0).payload.data())->flags =
        reader::kEntropyPlannedFlag;
    check(s, "CBK-E019", "CBK-E019");
    s = base;
    reinterpret_cast<reader::CompressedParallaxInfoRecord*>(find(s, 0).payload.data())->flags = 2;
    check(s, "CBK-E015", "CBK-E015");
  }
  {  // a corrupted block of a level-0 direction: opens, reads zeros, fails validation (and so do
     // the directions predicted from it, which decode against a zero plane)
    auto s = base;
    find(s, 3).payload[9] ^= std::byte{0x10};  // the rANS state of block 0
    check(s, "", "CBK-E021");
  }
}

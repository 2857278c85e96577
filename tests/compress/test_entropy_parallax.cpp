// The entropy-coded parallax form (format 1.2: compress/parallax_entropy.hpp writes it,
// formats/reader/parallax_entropy.hpp decodes it) through the writer and the reader: it decodes to
// exactly the 8-bit codes of the format 1.1 form on woven, tall, spiky and flat fields (flat stays
// exactly 0), answers every query identically, uses the tile's self-similarity, is byte-identical
// for any thread count, and hostile sections and blocks fail with stable IDs without reading out
// of bounds (every single-byte corruption and truncation of a block).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <set>
#include <string>

#include "compress/parallax_codes.hpp"
#include "compress/parallax_entropy.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/scene_plan_sections.hpp"
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
using reader::SectionType;

namespace {

using compress::test::baked;
using compress::test::spiky_maps;
using test_support::MemoryAsset;
using test_support::validate_ids;
using test_support::with_metadata;

compress::QuantisedParallax eight_bits(const ParallaxTable& t) {
  return compress::quantise_parallax({t.depth.data(), t.resolution, t.dirs, t.min_cos,
                                      t.depth_scale, t.reference_height, t.stats.max_sideways},
                                     1.0);
}

// Entropy form and 1.1 form of one table decode to the same codes and answer alike.
void expect_same_as_plain_codes(const ParallaxTable& table, const char* what) {
  const compress::QuantisedParallax p = eight_bits(table);
  const compress::EntropyParallax coded = compress::entropy_code_parallax(p);
  MemoryAsset e(with_metadata(compress::entropy_parallax_sections(p, coded)));
  MemoryAsset plain(with_metadata(compress::compressed_parallax_sections(p)));
  ASSERT_TRUE(e.status.ok()) << e.status.message();
  EXPECT_EQ(e.asset.version_minor(), 2) << what;
  reader::ParallaxView a, b;
  ASSERT_TRUE(a.open(e.asset).ok());
  ASSERT_TRUE(b.open(plain.asset).ok());
  EXPECT_TRUE(a.is_entropy_coded());
  EXPECT_TRUE(a.is_compressed());
  EXPECT_FALSE(b.is_entropy_coded());
  EXPECT_EQ(a.decoded_bytes(), 0u) << "nothing decoded at open";
  EXPECT_TRUE(a.decode_all().ok()) << what;
  const uint32_t n = a.resolution(), d = a.dirs() * a.dirs();
  for (uint32_t bin = 0; bin < d; ++bin)
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x)
        ASSERT_EQ(a.bin_code(bin, x, y), p.codes[(uint64_t(bin) * n + y) * n + x])
            << what << " bin " << bin << " texel " << x << ", " << y;
  const double views[3][3] = {{0.2, -0.4, 0.8}, {-0.7, 0.1, 0.3}, {0, 0, 1}};
  for (const auto& v : views) {
    reader::ParallaxSample sa, sb;
    ASSERT_TRUE(a.depth(-3, 21, v, &sa).ok());
    ASSERT_TRUE(b.depth(-3, 21, v, &sb).ok());
    EXPECT_EQ(sa.r, sb.r);
    ASSERT_TRUE(a.footprint_depth({-5.25, 3, 30, 17.5}, v, &sa).ok());
    ASSERT_TRUE(b.footprint_depth({-5.25, 3, 30, 17.5}, v, &sb).ok());
    EXPECT_EQ(sa.r, sb.r);
  }
  EXPECT_EQ(validate_ids(e.asset), "") << what;
}

}  // namespace

TEST(EntropyParallax, DecodesToTheEightBitCodesOnWovenTallSpikyAndFlatFields) {
  expect_same_as_plain_codes(baked(rctest::plain_weave_maps(16)), "plain weave");
  expect_same_as_plain_codes(baked(rctest::plain_weave_maps(24, 2, 0.4, 0.1), 6), "tall yarns");
  expect_same_as_plain_codes(baked(spiky_maps()), "spikes");
  // Flat: every step 0 and every code 0, decoded as exactly r = 0.
  const ParallaxTable flat = baked(rctest::maps_from(8, [](double, double) { return 0.25; }));
  expect_same_as_plain_codes(flat, "flat");
  const compress::QuantisedParallax p = eight_bits(flat);
  MemoryAsset m(
      with_metadata(compress::entropy_parallax_sections(p, compress::entropy_code_parallax(p))));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  reader::ParallaxSample s;
  const double v[3] = {0.5, 0.1, 0.7};
  ASSERT_TRUE(view.footprint_depth({-3.5, 2, 20, 9.25}, v, &s).ok());
  EXPECT_EQ(s.r, 0.0);
  ASSERT_TRUE(view.depth(3, -2, v, &s).ok());
  EXPECT_EQ(s.r, 0.0);
}

TEST(EntropyParallax, UsesTheTilesRepeatAndIsDeterministic) {
  // A plain weave of 4 threads on 32^2 repeats after (16, 16) (and (16, 0), (0, 16)).
  const ParallaxTable table = baked(rctest::plain_weave_maps(32, 4), 4);
  const compress::QuantisedParallax p = eight_bits(table);
  const compress::EntropyParallax coded = compress::entropy_code_parallax(p);
  ASSERT_FALSE(coded.candidates.empty());
  EXPECT_GT(coded.shifted_blocks, 0u);
  // Without the shift the same plane costs more.
  const uint32_t n = 32, mid = 2 * 4 + 2;
  const uint8_t* plane = p.codes.data() + mid * n * n;
  const auto [sx, sy] = coded.candidates[0];
  const std::vector<uint16_t> f0 =
      compress::parallax_frequencies(compress::parallax_residual_counts(plane, n, 0, 0));
  const std::vector<uint16_t> f1 =
      compress::parallax_frequencies(compress::parallax_residual_counts(plane, n, sx, sy));
  EXPECT_LT(compress::encode_parallax_block(plane, n, sx, sy, 0, f1.data()).size(),
            compress::encode_parallax_block(plane, n, 0, 0, 0, f0.data()).size());
  // Byte-identical with one thread.
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const compress::EntropyParallax again = compress::entropy_code_parallax(p);
  EXPECT_EQ(again.stream, coded.stream);
  EXPECT_EQ(again.offsets, coded.offsets);
  EXPECT_EQ(again.tables, coded.tables);
}

TEST(EntropyParallax, EveryCorruptionOrTruncationOfABlockIsSafe) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16), 2);
  const compress::QuantisedParallax p = eight_bits(table);
  const uint32_t n = 16;
  const std::vector<uint16_t> f =
      compress::parallax_frequencies(compress::parallax_residual_counts(p.codes.data(), n, 0, 0));
  const std::vector<uint8_t> block =
      compress::encode_parallax_block(p.codes.data(), n, 0, 0, 0, f.data());
  reader::ParallaxEntropyScratch scratch;
  std::vector<uint8_t> plane(n * n);
  ASSERT_TRUE(reader::decode_parallax_block(block.data(), block.size(), f.data(), 1, n,
                                            plane.data(), &scratch)
                  .ok());
  EXPECT_TRUE(std::equal(plane.begin(), plane.end(), p.codes.begin()));
  int detected = 0, total = 0;
  for (std::size_t i = 0; i < block.size(); ++i)
    for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80)}) {
      std::vector<uint8_t> bad = block;  // exact size: ASan sees any read past it
      bad[i] ^= flip;
      const reader::Status s = reader::decode_parallax_block(bad.data(), bad.size(), f.data(), 1, n,
                                                             plane.data(), &scratch);
      ++total;
      if (!s.ok()) {
        ++detected;
        EXPECT_EQ(std::string(reader::check_id(s.check())), "CBK-E021");
      }
    }
  EXPECT_GE(detected, total * 9 / 10) << "the final-state check catches almost every flip";
  for (std::size_t len = 0; len < block.size(); ++len) {
    std::vector<uint8_t> cut(block.begin(), block.begin() + std::ptrdiff_t(len));
    const reader::Status s = reader::decode_parallax_block(cut.data(), cut.size(), f.data(), 1, n,
                                                           plane.data(), &scratch);
    EXPECT_FALSE(s.ok()) << len;
    EXPECT_EQ(std::string(reader::check_id(s.check())), "CBK-E021");
  }
  // A group beyond the tables, a shift outside the tile.
  std::vector<uint8_t> bad = block;
  bad[4] = 1;
  EXPECT_FALSE(
      reader::decode_parallax_block(bad.data(), bad.size(), f.data(), 1, n, plane.data(), &scratch)
          .ok());
  bad = block;
  bad[0] = 16;
  EXPECT_FALSE(
      reader::decode_parallax_block(bad.data(), bad.size(), f.data(), 1, n, plane.data(), &scratch)
          .ok());
}

TEST(EntropyParallax, HostileSectionsFailWithStableIds) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(8), 4);
  const compress::QuantisedParallax p = eight_bits(table);
  const auto base =
      with_metadata(compress::entropy_parallax_sections(p, compress::entropy_code_parallax(p)));
  const auto find = compress::test::parallax_entropy_section;
  const auto check = compress::test::expect_hostile_parallax;
  {
    MemoryAsset m(base);
    EXPECT_EQ(validate_ids(m.asset), "");
  }
  {  // bits other than 8
    auto s = base;
    reinterpret_cast<reader::CompressedParallaxInfoRecord*>(find(s, 0).payload.data())->bits = 16;
    check(s, "CBK-E015", "CBK-E015");
  }
  {  // offsets that do not end at the stream's size
    auto s = base;
    auto& o = find(s, 2);
    reinterpret_cast<uint64_t*>(o.payload.data())[16] += 1;
    check(s, "CBK-E021", "CBK-E021");
  }
  {  // offsets that decrease
    auto s = base;
    auto& o = find(s, 2);
    auto* v = reinterpret_cast<uint64_t*>(o.payload.data());
    v[3] = v[5] + 1;
    check(s, "CBK-E021", "CBK-E021");
  }
  {  // frequency tables that do not sum to 4096
    auto s = base;
    auto* t = reinterpret_cast<uint16_t*>(find(s, 4).payload.data());
    t[0] = uint16_t(t[0] + 1);
    check(s, "CBK-E021", "CBK-E021");
  }
  {  // tables of the wrong shape
    auto s = base;
    find(s, 4) = formats::make_array_section<uint16_t>(
        SectionType::ParallaxEntropy, 4, std::vector<uint16_t>(4 * 256, 0), {1, 4, 256});
    check(s, "CBK-E015", "CBK-E015");
  }
  {  // the stream missing
    auto s = base;
    s.erase(std::find_if(s.begin(), s.end(), [](const formats::Section& x) {
      return x.type == SectionType::ParallaxEntropy && x.instance == 3;
    }));
    check(s, "CBK-E019", "CBK-E019");
  }
  {  // a corrupted block (valid checksum: a crafted asset) opens, reads zeros, fails validation
    auto s = base;
    auto& stream = find(s, 3);
    stream.payload[9] ^= std::byte{0x10};  // the rANS state of block 0
    check(s, "", "CBK-E021");
  }
}

// The planned form (format 1.3): a table coded with a keep mask stores the left-out directions as
// empty blocks; bin_map instance 1 gives the coverage. Kept directions decode to exactly the full
// table's codes; every query whose bilinear bins include a left-out one answers OutOfPlan (never
// a number); the asset is smaller than the full one; a 1.2 reader's check (flags) refuses it.
TEST(EntropyParallax, APlannedTableCoversExactlyItsBinMap) {
  const ParallaxTable table = baked(rctest::plain_weave_maps(16), 8);
  const compress::QuantisedParallax p = eight_bits(table);
  const uint32_t dirs = 8, bins = dirs * dirs, n = 16;
  std::vector<uint8_t> keep(bins, 0);
  for (uint32_t j = 2; j < 6; ++j)
    for (uint32_t i = 2; i < 6; ++i)
      keep[j * dirs + i] = 1;
  const compress::EntropyParallax full = compress::entropy_code_parallax(p);
  const compress::EntropyParallax coded = compress::entropy_code_parallax(p, keep);
  for (uint32_t b = 0; b < bins; ++b)
    EXPECT_EQ(coded.offsets[b + 1] == coded.offsets[b], keep[b] == 0) << "bin " << b;
  EXPECT_LT(coded.stream.size(), full.stream.size() / 2);
  auto sections = compress::planned_entropy_parallax_sections(p, coded, keep);
  sections.push_back(formats::make_array_section<uint8_t>(SectionType::BinMap, reader::kViewBinMap,
                                                          keep, {dirs, dirs}));
  MemoryAsset m(with_metadata(sections));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  EXPECT_EQ(m.asset.version_minor(), 3);
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  EXPECT_TRUE(view.is_entropy_coded());
  EXPECT_TRUE(view.is_planned());
  EXPECT_EQ(view.stored_dirs(), 16u);
  EXPECT_TRUE(view.decode_all().ok());
  EXPECT_EQ(validate_ids(m.asset), "");
  for (uint32_t b = 0; b < bins; ++b) {
    ASSERT_EQ(view.covers(b), keep[b] != 0) << "bin " << b;
    if (!keep[b]) {
      EXPECT_FALSE(view.ensure_plane(b));
      EXPECT_EQ(view.depth_step(b), 0.0);
      continue;
    }
    EXPECT_EQ(view.depth_step(b), p.steps[b]);
    for (uint32_t t = 0; t < n * n; ++t)
      ASSERT_EQ(view.bin_code(b, t % n, t / n), p.codes[uint64_t(b) * n * n + t]) << b << " " << t;
  }
  EXPECT_EQ(view.decoded_bytes(), 16u * n * n) << "left-out blocks are never decoded";
  // Views over the whole cap: OutOfPlan exactly when a bin of the bilinear lookup is left out.
  const model::DirectionGrid<double> grid{int(dirs), table.min_cos};
  int out_of_plan = 0, answered = 0;
  for (int a = 0; a < 24; ++a)
    for (int e = 0; e < 8; ++e) {
      const double phi = a * 0.2618, sin_t = e / 8.0;
      const double v[3] = {sin_t * std::cos(phi), sin_t * std::sin(phi),
                           std::sqrt(1 - sin_t * sin_t)};
      reader::ParallaxSample s, s_full;
      double o[3];
      ASSERT_TRUE(view.view_direction(v, o).ok());
      const auto w = grid.bilinear_fast(model::Vec3d(o[0], o[1], o[2]));
      bool covered = true;
      for (int k = 0; k < 4; ++k)
        covered = covered && (w.weight[k] <= 0.0 || keep[uint32_t(w.index[k])]);
      const reader::Status st = view.depth(3, -2, v, &s);
      const reader::Status fp = view.footprint_depth({1.5, 2, 9, 7.25}, v, &s_full);
      if (covered) {
        ++answered;
        EXPECT_TRUE(st.ok()) << st.message();
        EXPECT_TRUE(fp.ok()) << fp.message();
      } else {
        ++out_of_plan;
        EXPECT_EQ(st.code(), ErrorCode::OutOfPlan);
        EXPECT_EQ(fp.code(), ErrorCode::OutOfPlan);
      }
    }
  EXPECT_GT(out_of_plan, 0);
  EXPECT_GT(answered, 0);
  // Kept directions answer exactly as the full entropy-coded table.
  MemoryAsset whole(with_metadata(compress::entropy_parallax_sections(p, full)));
  reader::ParallaxView all;
  ASSERT_TRUE(all.open(whole.asset).ok());
  const double straight[3] = {0, 0, 1};
  reader::ParallaxSample a, b;
  ASSERT_TRUE(view.depth(5, 7, straight, &a).ok());
  ASSERT_TRUE(all.depth(5, 7, straight, &b).ok());
  EXPECT_EQ(a.r, b.r);
  EXPECT_LT(
      formats::serialize_asset(with_metadata(sections)).size(),
      formats::serialize_asset(with_metadata(compress::entropy_parallax_sections(p, full))).size());

  auto find_info = [](std::vector<formats::Section>& s) -> reader::CompressedParallaxInfoRecord* {
    for (auto& x : s)
      if (x.type == SectionType::ParallaxEntropy && x.instance == 0)
        return reinterpret_cast<reader::CompressedParallaxInfoRecord*>(x.payload.data());
    return nullptr;
  };
  {  // without its bin map a planned table does not open (never numbers for left-out bins)
    auto s = sections;
    s.pop_back();
    MemoryAsset bad(with_metadata(s));
    reader::ParallaxView v;
    EXPECT_EQ(v.open(bad.asset).code(), ErrorCode::NotFound);
  }
  {  // a bin map that disagrees with the empty blocks
    auto s = sections;
    std::vector<uint8_t> other = keep;
    other[0] = 1;
    s.back() = formats::make_array_section<uint8_t>(SectionType::BinMap, reader::kViewBinMap, other,
                                                    {dirs, dirs});
    MemoryAsset bad(with_metadata(s));
    reader::ParallaxView v;
    const reader::Status st = v.open(bad.asset);
    EXPECT_EQ(std::string(reader::check_id(st.check())), "CBK-E021") << st.message();
  }
  {  // an unknown flag bit is refused, as a 1.2 reader refuses the planned flag
    auto s = sections;
    find_info(s)->flags |= 2;
    MemoryAsset bad(with_metadata(s));
    reader::ParallaxView v;
    EXPECT_EQ(v.open(bad.asset).code(), ErrorCode::Unsupported);
  }
  // Deterministic for any thread count.
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const compress::EntropyParallax again = compress::entropy_code_parallax(p, keep);
  EXPECT_EQ(again.stream, coded.stream);
  EXPECT_EQ(again.tables, coded.tables);
}

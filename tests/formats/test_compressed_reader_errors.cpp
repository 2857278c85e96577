// The reader refuses damaged compressed tables with the documented error classes instead of
// indexing out of bounds: every count, index and value range is checked at open().
#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>

#include "formats/reader/scene_plan_sections.hpp"
#include "tests/support/compress_test_util.hpp"

namespace clothbake::compress {
namespace {

using reader::CompressedPart;
using reader::ErrorCode;

std::vector<formats::Section> good_sections() {
  CpcaOptions o;
  o.clusters_per_stratum = 2;
  o.rank = 2;
  return compressed_sections(compress_tables(test::synthetic_texels(12, 2, 3, 4), o));
}

formats::Section& part(std::vector<formats::Section>& s, CompressedPart p) {
  for (auto& x : s)
    if (x.instance == reader::compressed_instance(reader::RadianceTableKind::Specular, p)) return x;
  throw std::runtime_error("missing part");
}

reader::Status open(const std::vector<formats::Section>& sections) {
  const auto asset = test::memory_asset(sections);
  reader::CompressedRadianceTables t;
  const reader::Status s = t.open(asset->asset, reader::RadianceTableKind::Specular);
  if (s.ok()) {
    EXPECT_TRUE(t.is_open());
  }
  return s;
}

TEST(CompressedReaderErrors, GoodTablesOpen) {
  EXPECT_TRUE(open(good_sections()).ok());
}

TEST(CompressedReaderErrors, MissingKindOrPart) {
  auto s = good_sections();
  const auto asset = test::memory_asset(s);
  reader::CompressedRadianceTables t;
  EXPECT_EQ(t.open(asset->asset, reader::RadianceTableKind::Gap).code(), ErrorCode::NotFound);
  EXPECT_FALSE(t.is_open());
  s.erase(s.begin() + 3);
  EXPECT_EQ(open(s).code(), ErrorCode::NotFound);
}

TEST(CompressedReaderErrors, DamagedFields) {
  using Mutation = void (*)(std::vector<formats::Section>&);
  const std::vector<std::pair<const char*, Mutation>> cases = {
      {"cell map names a cell that does not exist",
       [](auto& s) { part(s, CompressedPart::CellMap).payload[7] = std::byte{200}; }},
      {"cell texel count disagrees with the map",
       [](auto& s) {
         auto& p = part(s, CompressedPart::CellMap).payload;
         for (auto& b : p)
           if (b != std::byte{255}) {
             b = std::byte{255};
             break;
           }
       }},
      {"cell rank changed (image count mismatch)",
       [](auto& s) {
         reinterpret_cast<uint32_t*>(part(s, CompressedPart::Cells).payload.data())[1] += 1;
       }},
      {"clusters out of order",
       [](auto& s) {
         auto* c = reinterpret_cast<uint32_t*>(part(s, CompressedPart::Cells).payload.data());
         c[0] = 2;
       }},
      {"negative scale",
       [](auto& s) {
         reinterpret_cast<float*>(part(s, CompressedPart::Scales).payload.data())[0] = -1.0f;
       }},
      {"basis value outside [-1, 1]",
       [](auto& s) {
         reinterpret_cast<uint16_t*>(part(s, CompressedPart::Basis).payload.data())[3] = 0x4000;
       }},
      {"basis NaN",
       [](auto& s) {
         reinterpret_cast<uint16_t*>(part(s, CompressedPart::Basis).payload.data())[3] = 0x7e00;
       }},
      {"coefficient -32768",
       [](auto& s) {
         reinterpret_cast<int16_t*>(part(s, CompressedPart::Coefficients).payload.data())[0] =
             INT16_MIN;
       }},
      {"info kind field",
       [](auto& s) {
         reinterpret_cast<reader::CompressedTableInfoRecord*>(
             part(s, CompressedPart::Info).payload.data())
             ->kind = 1;
       }},
      {"info image count",
       [](auto& s) {
         reinterpret_cast<reader::CompressedTableInfoRecord*>(
             part(s, CompressedPart::Info).payload.data())
             ->image_count = 5000;
       }},
      {"info NaN error",
       [](auto& s) {
         reinterpret_cast<reader::CompressedTableInfoRecord*>(
             part(s, CompressedPart::Info).payload.data())
             ->bake_error = NAN;
       }},
      {"basis shape",
       [](auto& s) {
         part(s, CompressedPart::Basis).dims = {
             2, uint32_t(part(s, CompressedPart::Basis).payload.size() / 4)};
       }},
  };
  for (const auto& [what, mutate] : cases) {
    auto s = good_sections();
    mutate(s);
    const reader::Status status = open(s);
    EXPECT_FALSE(status.ok()) << what;
    EXPECT_TRUE(status.code() == ErrorCode::Malformed || status.code() == ErrorCode::WrongType)
        << what << ": " << status.message();
  }
}

// The planned flag (info flags bit 0): it needs bin_map instance 0 of the tables' bins
// (CBK-E019 without it, CBK-E015 when its n differs); other flag bits are unknown (CBK-E015), and
// the one-bin gap kind is never planned (CBK-E015). With the map, only its bins answer.
TEST(CompressedReaderErrors, PlannedFlagNeedsItsBinMap) {
  auto flagged = [](uint32_t flags) {
    auto s = good_sections();
    std::memcpy(part(s, CompressedPart::Info).payload.data() +
                    offsetof(reader::CompressedTableInfoRecord, flags),
                &flags, 4);
    return s;
  };
  reader::Status st = open(flagged(reader::kCompressedPlannedFlag));
  EXPECT_EQ(st.code(), ErrorCode::NotFound) << st.message();
  EXPECT_STREQ(st.check_id(), "CBK-E019");
  st = open(flagged(2));
  EXPECT_STREQ(st.check_id(), "CBK-E015") << st.message();
  // With a bin map of the tables' n (4 x 4 bins here) that keeps bin 0 only.
  uint32_t n = 0;
  {
    const auto s = good_sections();
    reader::CompressedTableInfoRecord info;
    std::memcpy(&info, s[0].payload.data(), sizeof info);
    n = info.bins_per_side;
  }
  std::vector<uint8_t> keep(std::size_t(n) * n, 0);
  keep[0] = 1;
  auto s = flagged(reader::kCompressedPlannedFlag);
  s.push_back(formats::make_array_section<uint8_t>(reader::SectionType::BinMap,
                                                   reader::kHalfVectorBinMap, keep, {n, n}));
  const auto asset = test::memory_asset(s);
  reader::CompressedRadianceTables t;
  ASSERT_TRUE(t.open(asset->asset, reader::RadianceTableKind::Specular).ok());
  EXPECT_TRUE(t.is_planned());
  // Bin 0 is the corner of the square (u, v < 1/n): a half vector whose lookup stays within half a
  // bin of that corner is answered, the zenith (the middle bins) is not.
  const double corner[3] = {-1, -1, 0.01}, zenith[3] = {0, 0, 1};
  EXPECT_TRUE(t.covers_bins(corner));
  EXPECT_FALSE(t.covers_bins(zenith));
  // A map of another n.
  auto wrong = flagged(reader::kCompressedPlannedFlag);
  std::vector<uint8_t> other((n + 1) * (n + 1), 1);
  wrong.push_back(formats::make_array_section<uint8_t>(
      reader::SectionType::BinMap, reader::kHalfVectorBinMap, other, {n + 1, n + 1}));
  EXPECT_STREQ(open(wrong).check_id(), "CBK-E015");
}

// A planned kind's basis (part 4) holds the columns of its covered bins only, {images, K}, in bin
// order; the all-columns form {images, B} (left-out columns zero, written before that rule) reads
// the same, value for value; any other column count is CBK-E015.
TEST(CompressedReaderErrors, PlannedBasisStoresTheCoveredColumnsOnly) {
  auto planned = [](const std::vector<uint8_t>& keep, uint32_t n, bool compact, int extra = 0) {
    auto s = good_sections();
    const uint32_t flags = reader::kCompressedPlannedFlag;
    std::memcpy(part(s, CompressedPart::Info).payload.data() +
                    offsetof(reader::CompressedTableInfoRecord, flags),
                &flags, 4);
    formats::Section& basis = part(s, CompressedPart::Basis);
    const uint32_t images = basis.dims[0], bins = basis.dims[1];
    std::vector<uint16_t> all(std::size_t(images) * bins);
    std::memcpy(all.data(), basis.payload.data(), all.size() * 2);
    std::vector<uint16_t> stored;
    for (uint32_t i = 0; i < images; ++i)
      for (uint32_t b = 0; b < bins; ++b)
        if (keep[b])
          stored.push_back(all[std::size_t(i) * bins + b]);
        else if (!compact)
          stored.push_back(0);  // +0 in f16
    const uint32_t columns = uint32_t(stored.size() / images);
    for (int k = 0; k < extra * int(images); ++k)
      stored.push_back(0);
    basis.payload.resize(stored.size() * 2);
    std::memcpy(basis.payload.data(), stored.data(), stored.size() * 2);
    basis.dims = {images, columns + uint32_t(extra)};
    s.push_back(formats::make_array_section<uint8_t>(reader::SectionType::BinMap,
                                                     reader::kHalfVectorBinMap, keep, {n, n}));
    return s;
  };
  uint32_t n = 0;
  {
    const auto s = good_sections();
    reader::CompressedTableInfoRecord info;
    std::memcpy(&info, s[0].payload.data(), sizeof info);
    n = info.bins_per_side;
  }
  // The first and the last bin kept (n >= 2): the corner (-1, -1) is answered from bin 0 alone.
  ASSERT_GE(n, 2u);
  std::vector<uint8_t> keep(std::size_t(n) * n, 0);
  keep[0] = keep.back() = 1;
  const auto compact = test::memory_asset(planned(keep, n, true));
  const auto wide = test::memory_asset(planned(keep, n, false));
  reader::CompressedRadianceTables a, b;
  ASSERT_TRUE(a.open(compact->asset, reader::RadianceTableKind::Specular).ok());
  ASSERT_TRUE(b.open(wide->asset, reader::RadianceTableKind::Specular).ok());
  for (uint32_t bin = 0; bin < n * n; ++bin)
    for (uint32_t image = 0; image < a.image_count(); ++image)
      ASSERT_EQ(a.image_basis(image, bin), b.image_basis(image, bin)) << bin << " " << image;
  const double corner[3] = {-1, -1, 0.01};
  double va[3] = {}, vb[3] = {};
  ASSERT_TRUE(a.query_all({0, 0, 1, 1}, corner, va).ok());
  ASSERT_TRUE(b.query_all({0, 0, 1, 1}, corner, vb).ok());
  EXPECT_EQ(va[0], vb[0]);
  // A left-out bin's column is zero; a kept one's is the full table's.
  const auto full = test::memory_asset(good_sections());
  reader::CompressedRadianceTables f;
  ASSERT_TRUE(f.open(full->asset, reader::RadianceTableKind::Specular).ok());
  for (uint32_t image = 0; image < a.image_count(); ++image) {
    EXPECT_EQ(a.image_basis(image, n * n - 1), f.image_basis(image, n * n - 1));
    EXPECT_EQ(a.image_basis(image, 0), f.image_basis(image, 0));
    EXPECT_EQ(a.image_basis(image, 1), 0.0f);
  }
  // Neither K nor B columns.
  reader::Status st = open(planned(keep, n, true, 1));
  EXPECT_STREQ(st.check_id(), "CBK-E015") << st.message();
}

TEST(CompressedReaderErrors, BadQueryArguments) {
  const auto asset = test::memory_asset(good_sections());
  reader::CompressedRadianceTables t;
  ASSERT_TRUE(t.open(asset->asset, reader::RadianceTableKind::Specular).ok());
  const double h[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
  double out[3];
  EXPECT_EQ(t.query({0, 0, 1, 1}, h, 3, out).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query_all({0, 0, NAN, 1}, h, out).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query_all({2, 0, 1, 1}, h, out).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query_all({0, 0, 1, 1}, zero, out).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query_all({0, 0, 1, 1}, h, nullptr).code(), ErrorCode::InvalidArgument);
  EXPECT_FALSE(t.try_query_all({0, 0, 1, 1}, zero, out));
  reader::CompressedRadianceTables closed;
  EXPECT_EQ(closed.query_all({0, 0, 1, 1}, h, out).code(), ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace clothbake::compress

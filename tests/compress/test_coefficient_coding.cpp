// The entropy-coded C-PCA coefficients (compress/coefficient_coding.hpp writes part 5,
// formats/reader/compressed_coefficients.hpp decodes it): lossless (the decoded coefficients are
// exactly the set's, and every table value is the set's C-PCA sum), a tile that repeats is coded
// through its shift, tiny tables are coded too, and damaged streams or the retired plain i16
// part fail with stable IDs without reading out of bounds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "compress/coefficient_coding.hpp"
#include "formats/reader/compressed_coefficients.hpp"
#include "tests/support/compress_test_util.hpp"

namespace clothbake::compress {
namespace {

using reader::CompressedPart;
using reader::ErrorCode;

CompressedTableSet tables_of(int n, uint64_t seed, int rank = 4) {
  CpcaOptions o;
  o.clusters_per_stratum = 2;
  o.rank = rank;
  return compress_tables(test::synthetic_texels(n, 4, 3, seed), o);
}

bool has_part(const std::vector<formats::Section>& s, CompressedPart p) {
  return std::any_of(s.begin(), s.end(), [&](const formats::Section& x) {
    return x.instance == reader::compressed_instance(reader::RadianceTableKind::Specular, p);
  });
}

formats::Section& part(std::vector<formats::Section>& s, CompressedPart p) {
  for (auto& x : s)
    if (x.instance == reader::compressed_instance(reader::RadianceTableKind::Specular, p)) return x;
  throw std::runtime_error("missing part");
}

reader::Status open(const std::vector<formats::Section>& sections,
                    reader::CompressedRadianceTables* t) {
  const auto asset = test::memory_asset(sections);
  return t->open(asset->asset, reader::RadianceTableKind::Specular);
}

}  // namespace

// The decompressed value of texel t in `bin` straight from the set (compressed_layout.hpp).
double set_value(const CompressedTableSet& set, uint64_t t, uint32_t bin) {
  const uint8_t g = set.cell_map[t];
  if (g == reader::kNoCell) return 0.0;
  const reader::CompressedCell& cell = set.cells[g];
  const uint32_t bins = set.info.bins_per_side * set.info.bins_per_side;
  uint64_t first = 0;  // the texel's first coefficient
  for (uint64_t u = 0; u < t; ++u)
    if (set.cell_map[u] != reader::kNoCell) first += set.cells[set.cell_map[u]].rank;
  auto image = [&](uint32_t i) {
    return double(set.scales[i] * reader::half_to_float(set.basis[uint64_t(i) * bins + bin]));
  };
  double v = image(cell.first_image);
  for (uint32_t j = 0; j < cell.rank; ++j)
    v += double(set.coefficients[first + j]) * image(cell.first_image + 1 + j);
  return v;
}

TEST(CoefficientCoding, IsLosslessThroughTheReader) {
  for (uint64_t seed : {1u, 2u, 7u}) {
    const CompressedTableSet set = tables_of(64, seed, 8);
    ASSERT_FALSE(set.coefficients.empty());
    std::vector<formats::Section> coded = compressed_sections(set);
    EXPECT_EQ(part(coded, CompressedPart::Coefficients).element, reader::ElementType::U8);
    EXPECT_LT(part(coded, CompressedPart::Coefficients).payload.size(),
              set.coefficients.size() * 2);
    reader::CompressedRadianceTables b;
    const reader::Status s = open(coded, &b);
    ASSERT_TRUE(s.ok()) << s.message();
    const uint32_t n = set.info.resolution, bins = 16;
    EXPECT_EQ(n, 64u);
    for (uint32_t bin = 0; bin < bins; bin += 5)
      for (uint32_t y = 0; y < n; y += 3)
        for (uint32_t x = 0; x < n; ++x) {
          const double want = set_value(set, uint64_t(y) * n + x, bin);
          ASSERT_NEAR(b.texel_value(bin, x, y), want, 1e-6 * std::fabs(want) + 1e-30)
              << bin << " " << x << " " << y;
        }
    // The decoder alone gives exactly the set's coefficients.
    std::vector<uint32_t> first(uint64_t(n) * n), ranks;
    for (const auto& c : set.cells)
      ranks.push_back(c.rank);
    uint64_t next = 0;
    for (uint64_t t = 0; t < first.size(); ++t) {
      first[t] = uint32_t(next);
      if (set.cell_map[t] != reader::kNoCell) next += ranks[set.cell_map[t]];
    }
    const std::vector<uint8_t> stream = code_compressed_coefficients(set);
    std::vector<int16_t> out(set.coefficients.size());
    ASSERT_TRUE(reader::decode_compressed_coefficients(stream.data(), stream.size(), n,
                                                       set.cell_map.data(), ranks.data(),
                                                       first.data(), out.size(), out.data())
                    .ok());
    EXPECT_EQ(out, set.coefficients);
  }
}

TEST(CoefficientCoding, ARepeatingTileIsCodedThroughItsShift) {
  // The synthetic texels repeat with period (35, 35) only by accident; build a tile that repeats
  // exactly after (16, 16): the 32^2 tile is four copies of a 16^2 one.
  DirectionalTexels small = test::synthetic_texels(16, 4, 3, 5), big = small;
  big.resolution = 32;
  const std::size_t bins = std::size_t(small.bins());
  big.cluster.assign(32 * 32, 0);
  big.values.assign(32 * 32 * bins, 0.0f);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const std::size_t t = std::size_t(y) * 32 + std::size_t(x);
      const std::size_t s = std::size_t(y % 16) * 16 + std::size_t(x % 16);
      big.cluster[t] = small.cluster[s];
      std::copy_n(small.values.begin() + std::ptrdiff_t(s * bins), bins,
                  big.values.begin() + std::ptrdiff_t(t * bins));
    }
  CpcaOptions o;
  o.clusters_per_stratum = 1;
  o.rank = 4;
  const CompressedTableSet set = compress_tables(big, o);
  const std::vector<uint8_t> plain = encode_compressed_coefficients(set, 0, 0);
  const std::vector<uint8_t> shifted = encode_compressed_coefficients(set, 16, 16);
  EXPECT_LT(shifted.size(), plain.size());
  EXPECT_LE(code_compressed_coefficients(set).size(), shifted.size());
}

TEST(CoefficientCoding, TinyTablesAreCodedToo) {
  // One bin (like the gap kind): the stream's 2 KB of tables exceed the raw coefficients, and the
  // one form is kept anyway.
  const CompressedTableSet set = compress_tables(test::synthetic_texels(6, 1, 2, 3), CpcaOptions{});
  const std::vector<formats::Section> s = compressed_sections(set);
  const auto asset = test::memory_asset(s);
  reader::CompressedRadianceTables t;
  const reader::Status st = t.open(asset->asset, reader::RadianceTableKind(set.info.kind));
  ASSERT_TRUE(st.ok()) << st.message();
  for (uint32_t y = 0; y < 6; ++y)
    for (uint32_t x = 0; x < 6; ++x) {
      const double want = set_value(set, uint64_t(y) * 6 + x, 0);
      EXPECT_NEAR(t.texel_value(0, x, y), want, 1e-6 * std::fabs(want) + 1e-30);
    }
}

TEST(CoefficientCoding, DamagedStreamsAndThePlainPartAreRefused) {
  const CompressedTableSet set = tables_of(48, 3, 8);
  std::vector<formats::Section> coded = compressed_sections(set);
  ASSERT_TRUE(has_part(coded, CompressedPart::Coefficients));
  const std::vector<std::byte> good = part(coded, CompressedPart::Coefficients).payload;
  if (const char* dir = std::getenv("CLOTHBAKE_SAVE_CRAFTED")) {
    // How tests/fuzz/corpus/coded_coefficients.cbk was made: these 48^2 tables.
    std::vector<formats::Section> with_metadata = coded;
    with_metadata.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
    const auto bytes = formats::serialize_asset(with_metadata);
    std::ofstream(std::string(dir) + "/coded_coefficients.cbk", std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  int detected = 0, total = 0;
  for (std::size_t i = 0; i < good.size(); i += (i < 2100 ? 97 : 13)) {
    for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80)}) {
      std::vector<formats::Section> s = coded;
      part(s, CompressedPart::Coefficients).payload[i] ^= std::byte{flip};
      reader::CompressedRadianceTables t;
      const reader::Status st = open(s, &t);
      ++total;
      if (!st.ok()) {
        ++detected;
        EXPECT_EQ(std::string(st.check_id()), "CBK-E021") << i << ": " << st.message();
      }
    }
  }
  // A flip in the header, a table or a bit length is caught by the checks; a flip in the raw
  // mantissa bits decodes to other valid coefficients (a crafted asset may hold any
  // coefficients: what matters is that nothing reads out of bounds).
  EXPECT_GT(detected, total / 4);
  EXPECT_LT(detected, total);
  for (std::size_t len : {std::size_t(0), std::size_t(15), std::size_t(2063), good.size() - 1}) {
    std::vector<formats::Section> s = coded;
    part(s, CompressedPart::Coefficients).payload.resize(len);
    part(s, CompressedPart::Coefficients).dims = {uint32_t(len)};
    reader::CompressedRadianceTables t;
    const reader::Status st = open(s, &t);
    EXPECT_EQ(std::string(st.check_id()), "CBK-E021") << len << ": " << st.message();
  }
  {  // the plain i16 coefficients of format 1: not the 2.0 form
    std::vector<formats::Section> s = coded;
    part(s, CompressedPart::Coefficients) = formats::make_array_section<int16_t>(
        reader::SectionType::RadianceCompressedTables,
        reader::compressed_instance(reader::RadianceTableKind::Specular,
                                    CompressedPart::Coefficients),
        set.coefficients, {uint32_t(set.coefficients.size())});
    reader::CompressedRadianceTables t;
    EXPECT_EQ(std::string(open(s, &t).check_id()), "CBK-E015");
  }
}

}  // namespace clothbake::compress

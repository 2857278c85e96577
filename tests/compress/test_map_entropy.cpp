// Entropy-coded feature maps, the one stored form of height, tangent, normal, gap and albedo
// (compress/map_entropy.hpp and formats/reader/map_entropy.hpp): lossless against the 16-bit codes
// of fabric/fabric_sections.hpp, a fraction of their size on woven tiles, at most the tables more
// on noise, and hostile payloads (damaged blocks, offsets, tables, counts) reported with
// CBK-E021 / CBK-E015 / CBK-E016 without reading out of bounds.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>

#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/map_encoding.hpp"
#include "formats/reader/map_entropy.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"
#include "tests/support/fabric_asset_sections.hpp"

namespace {

using namespace clothbake;
using formats::Section;
using reader::SectionType;

std::vector<Section> sections_of(const Fabric& fabric) {
  auto s = test_support::fabric_asset_sections(fabric);
  s.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  return s;
}

// The floats a code array of feature_map_codes stands for (map_encoding.hpp's decoders).
std::vector<float> decode_code_array(const Section& codes) {
  const auto bytes = codes.bytes();
  const std::size_t count = bytes.size() / 2;
  std::vector<uint16_t> q(count);
  std::memcpy(q.data(), bytes.data(), bytes.size());
  std::vector<float> out;
  if (codes.type == SectionType::TangentMap || codes.type == SectionType::NormalMap) {
    out.resize(count / 2 * 3);
    for (std::size_t t = 0; t < count / 2; ++t) {
      int16_t pair[2];
      std::memcpy(pair, q.data() + 2 * t, 4);
      reader::decode_octahedral(pair, out.data() + 3 * t);
    }
  } else {
    for (uint16_t c : q)
      out.push_back(codes.type == SectionType::HeightMap ? reader::half_to_float(reader::Half{c})
                                                         : reader::unorm16_to_float(c));
  }
  return out;
}

// The decoded maps equal the code arrays' values bit for bit, map by map.
void expect_lossless(const Fabric& fabric, const reader::FeatureMaps& maps) {
  for (const Section& codes : feature_map_codes(fabric.maps)) {
    if (codes.type == SectionType::YarnIdMap) continue;
    const std::vector<float> expected = decode_code_array(codes);
    const reader::ArrayView<float>& v = codes.type == SectionType::HeightMap    ? maps.height
                                        : codes.type == SectionType::TangentMap ? maps.tangent
                                        : codes.type == SectionType::NormalMap  ? maps.normal
                                        : codes.type == SectionType::GapMap     ? maps.gap
                                                                                : maps.albedo;
    ASSERT_EQ(v.size, expected.size()) << reader::section_type_name(codes.type);
    EXPECT_EQ(std::memcmp(v.data, expected.data(), expected.size() * 4), 0)
        << reader::section_type_name(codes.type);
  }
}

struct Opened {
  std::vector<uint64_t> words;
  reader::Asset asset;
  reader::Status status;
  explicit Opened(const std::vector<Section>& sections) {
    const auto bytes = formats::serialize_asset(sections);
    words.resize((bytes.size() + 7) / 8);
    std::memcpy(words.data(), bytes.data(), bytes.size());
    status = asset.open_memory(words.data(), bytes.size());
  }
};

std::vector<std::string> finding_ids(const reader::Asset& asset) {
  std::vector<std::string> ids;
  reader::validate_asset(
      asset,
      [](void* user, reader::Check check, uint32_t, const char*) {
        static_cast<std::vector<std::string>*>(user)->push_back(reader::check_id(check));
      },
      &ids);
  return ids;
}

bool has(const std::vector<std::string>& ids, const char* id) {
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

TEST(MapEntropy, LosslessAndSmallerOnAWovenTile) {
  // 128^2: large enough that the 2.5 KB frequency tables of each byte plane are paid back.
  const Fabric fabric = test_support::make_test_fabric(128);
  Opened coded(sections_of(fabric));
  ASSERT_TRUE(coded.status.ok()) << coded.status.message();
  EXPECT_EQ(coded.asset.version_major(), 2);
  EXPECT_EQ(coded.asset.version_minor(), 0);
  uint64_t code_bytes = 0, coded_bytes = 0;
  for (const Section& m : feature_map_codes(fabric.maps)) {
    if (m.type == SectionType::YarnIdMap) continue;
    reader::SectionInfo b;
    ASSERT_TRUE(coded.asset.find(m.type, 0, &b).ok());
    EXPECT_EQ(b.version, reader::kFeatureMapVersion) << reader::section_type_name(m.type);
    EXPECT_EQ(b.element_type, reader::ElementType::U8);
    code_bytes += m.payload.size();
    coded_bytes += b.stored_size;
  }
  // A periodic weave codes to a fraction; at 128^2 most of it is the 2.5 KB tables of each of the
  // 18 byte planes (46 KB), so the ratio is about 4 here and about 12 at 256^2 (the twill).
  EXPECT_LT(coded_bytes * 3, code_bytes);
  reader::FeatureMaps b;
  const reader::Status s = reader::read_feature_maps(coded.asset, &b);
  ASSERT_TRUE(s.ok()) << s.message();
  expect_lossless(fabric, b);
  EXPECT_TRUE(finding_ids(coded.asset).empty());
}

TEST(MapEntropy, NoisyMapsStayLosslessAndCostAtMostTheirTables) {
  Fabric fabric = test_support::make_test_fabric(48);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (std::size_t t = 0; t < fabric.maps.texel_count(); ++t) {
    fabric.maps.height[t] = u(rng) * 0.1f;
    fabric.maps.albedo[t] = {u(rng), u(rng), u(rng)};
  }
  for (const auto& m : feature_map_codes(fabric.maps)) {
    if (m.type == SectionType::YarnIdMap) continue;
    const Section c = compress::entropy_code_map(m);
    EXPECT_EQ(c.version, reader::kFeatureMapVersion);
    // Noise does not compress: the coded form costs at most its header, offsets and tables (and a
    // few bytes of coder state per plane) more than the code array.
    const std::size_t planes = m.payload.size() / (48 * 48);
    EXPECT_LE(c.payload.size(), m.payload.size() + reader::kMapEntropyHeaderBytes +
                                    8 * (planes + 1) +
                                    planes * (reader::kMapEntropyTableBytes + 16))
        << reader::section_type_name(m.type);
  }
  Opened coded(sections_of(fabric));
  ASSERT_TRUE(coded.status.ok());
  reader::FeatureMaps b;
  ASSERT_TRUE(reader::read_feature_maps(coded.asset, &b).ok());
  expect_lossless(fabric, b);
}

// The coded gap section of the 64^2 test fabric, for the damage tests.
Section coded_gap(const Fabric& fabric) {
  for (auto& m : compress::feature_map_sections(fabric.maps))
    if (m.type == SectionType::GapMap) return m;
  return {};
}

void replace(std::vector<Section>& sections, const Section& s) {
  for (auto& t : sections)
    if (t.type == s.type) t = s;
}

template <class T>
void poke(Section& s, std::size_t at, T v) {
  std::memcpy(s.payload.data() + at, &v, sizeof v);
}

// Opens the sections with `gap` instead of the coded gap map; expects read_feature_maps to fail
// with `code` and validate to report `id`.
void expect_refused(const Fabric& fabric, const Section& gap, reader::ErrorCode code,
                    const char* id) {
  auto sections = sections_of(fabric);
  replace(sections, gap);
  Opened opened(sections);
  ASSERT_TRUE(opened.status.ok()) << opened.status.message();
  reader::FeatureMaps maps;
  const reader::Status s = reader::read_feature_maps(opened.asset, &maps);
  EXPECT_EQ(s.code(), code) << s.message();
  EXPECT_STREQ(s.check_id(), id) << s.message();
  EXPECT_NE(std::string(s.message()).find("gap map"), std::string::npos) << s.message();
  EXPECT_TRUE(has(finding_ids(opened.asset), id));
}

TEST(MapEntropy, DamagedPayloadsAreReported) {
  const Fabric fabric = test_support::make_test_fabric(64);
  const Section good = coded_gap(fabric);
  if (const char* dir = std::getenv("CLOTHBAKE_SAVE_CRAFTED")) {
    // How tests/fuzz/corpus/map_entropy.cbk was made: the 64^2 fabric's coded maps.
    const auto bytes = formats::serialize_asset(sections_of(fabric));
    std::ofstream(std::string(dir) + "/map_entropy.cbk", std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  ASSERT_EQ(good.version, reader::kFeatureMapVersion);
  const std::size_t offsets = reader::kMapEntropyHeaderBytes;
  const std::size_t tables = offsets + 8 * 3;  // P = 2
  uint32_t groups = 0;  // one table set per plane or one shared: the encoder's choice
  std::memcpy(&groups, good.payload.data() + 8, 4);
  ASSERT_TRUE(groups == 1 || groups == 2) << groups;
  const std::size_t blocks = tables + groups * reader::kMapEntropyTableBytes;
  using reader::ErrorCode;
  {
    Section s = good;
    poke<uint32_t>(s, 4, 4);  // four planes for one channel
    expect_refused(fabric, s, ErrorCode::WrongType, "CBK-E015");
  }
  {
    Section s = good;
    poke<uint32_t>(s, 12, 1);  // reserved
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
  {
    Section s = good;
    poke<uint32_t>(s, 8, 3);  // more groups than planes
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
  {
    Section s = good;
    poke<uint64_t>(s, offsets + 8, ~0ull);  // plane 0 ends beyond the payload
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
  {
    Section s = good;
    poke<uint16_t>(s, tables + 2 * 7, 4096);  // a context sums to more than 4096
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
  {
    Section s = good;
    s.payload.resize(s.payload.size() - 1);  // the last block loses a byte
    s.dims = {uint32_t(s.payload.size())};
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
  {
    Section s = good;
    poke<uint8_t>(s, blocks + 8 + 1, 0xff);  // the first block's rANS state
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
  {
    Section s = good;
    poke<uint32_t>(s, 0, 32);  // N of another size than the other maps
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E016");
  }
  {
    Section s = good;
    s.payload.resize(10);  // shorter than the header
    s.dims = {10};
    expect_refused(fabric, s, ErrorCode::Malformed, "CBK-E021");
  }
}

TEST(MapEntropy, RandomDamageNeverCrashes) {
  // Every byte value at random positions: the reader reports or decodes, never reads out of
  // bounds (the fuzz harness and formats_reader_asan_test run the same decoder instrumented).
  const Fabric fabric = test_support::make_test_fabric(64);
  const Section good = coded_gap(fabric);
  std::mt19937 rng(4);
  int refused = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Section s = good;
    const int edits = 1 + trial % 4;
    for (int e = 0; e < edits; ++e)
      s.payload[rng() % s.payload.size()] = std::byte(rng() & 0xff);
    auto sections = sections_of(fabric);
    replace(sections, s);
    Opened opened(sections);
    ASSERT_TRUE(opened.status.ok());
    reader::FeatureMaps maps;
    if (!reader::read_feature_maps(opened.asset, &maps).ok()) ++refused;
    (void)finding_ids(opened.asset);
  }
  EXPECT_GT(refused, 100);
}

}  // namespace

// Entropy-coded feature maps (format 1.4, payload version 3; compress/map_entropy.hpp and
// formats/reader/map_entropy.hpp): lossless against the version-2 codes, smaller on woven tiles,
// never larger, and hostile payloads (damaged blocks, offsets, tables, counts) reported with
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
#include "formats/reader/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"

namespace {

using namespace clothbake;
using formats::Section;
using reader::SectionType;

std::vector<Section> sections_of(const Fabric& fabric, bool entropy) {
  auto s = fabric_record_sections(fabric);
  for (auto& m : feature_map_sections(fabric.maps, MapEncoding::Packed))
    s.push_back(entropy && m.version == reader::kFeatureMapPackedVersion
                    ? compress::entropy_code_map(m)
                    : std::move(m));
  s.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  return s;
}

struct Opened {
  std::vector<uint64_t> words;
  reader::Asset asset;
  reader::Status status;
  explicit Opened(const std::vector<Section>& sections) {
    const auto bytes = formats::serialize_asset(sections);
    words.resize((bytes.size() + 7) / 8);
    std::memcpy(words.data(), bytes.data(), bytes.size());
    status = asset.open_memory(words.data(), bytes.size(), {reader::Verify::Structure});
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

void expect_same_maps(const reader::FeatureMaps& a, const reader::FeatureMaps& b) {
  ASSERT_EQ(a.resolution, b.resolution);
  const uint64_t t = uint64_t(a.resolution) * a.resolution;
  ASSERT_EQ(std::memcmp(a.height.data, b.height.data, t * 4), 0);
  ASSERT_EQ(std::memcmp(a.tangent.data, b.tangent.data, t * 12), 0);
  ASSERT_EQ(std::memcmp(a.normal.data, b.normal.data, t * 12), 0);
  ASSERT_EQ(std::memcmp(a.gap.data, b.gap.data, t * 4), 0);
  ASSERT_EQ(std::memcmp(a.albedo.data, b.albedo.data, t * 12), 0);
}

TEST(MapEntropy, LosslessAndSmallerOnAWovenTile) {
  // 128^2: large enough that the 2.5 KB frequency tables of each byte plane are paid back.
  const Fabric fabric = test_support::make_test_fabric(128);
  Opened packed(sections_of(fabric, false)), coded(sections_of(fabric, true));
  ASSERT_TRUE(packed.status.ok());
  ASSERT_TRUE(coded.status.ok()) << coded.status.message();
  EXPECT_EQ(coded.asset.version_minor(), 4);
  uint64_t packed_bytes = 0, coded_bytes = 0;
  for (SectionType t : {SectionType::HeightMap, SectionType::TangentMap, SectionType::NormalMap,
                        SectionType::GapMap, SectionType::AlbedoMap}) {
    reader::SectionInfo a, b;
    ASSERT_TRUE(packed.asset.find(t, 0, &a).ok());
    ASSERT_TRUE(coded.asset.find(t, 0, &b).ok());
    EXPECT_EQ(b.version, reader::kFeatureMapEntropyVersion) << reader::section_type_name(t);
    packed_bytes += a.stored_size;
    coded_bytes += b.stored_size;
  }
  // A periodic weave codes to a fraction; at 128^2 most of it is the 2.5 KB tables of each of the
  // 18 byte planes (46 KB), so the ratio is about 4 here and about 12 at 256^2 (the twill).
  EXPECT_LT(coded_bytes * 3, packed_bytes);
  reader::FeatureMaps a, b;
  ASSERT_TRUE(reader::read_feature_maps(packed.asset, &a).ok());
  const reader::Status s = reader::read_feature_maps(coded.asset, &b);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(b.versions[3], reader::kFeatureMapEntropyVersion);
  expect_same_maps(a, b);
  EXPECT_TRUE(finding_ids(coded.asset).empty());
}

TEST(MapEntropy, NoisyMapsStayLosslessAndNeverGrow) {
  Fabric fabric = test_support::make_test_fabric(48);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (std::size_t t = 0; t < fabric.maps.texel_count(); ++t) {
    fabric.maps.height[t] = u(rng) * 0.1f;
    fabric.maps.albedo[t] = {u(rng), u(rng), u(rng)};
  }
  for (const auto& m : feature_map_sections(fabric.maps)) {
    if (m.version != reader::kFeatureMapPackedVersion) continue;
    const Section c = compress::entropy_code_map(m);
    EXPECT_LE(c.payload.size(), m.payload.size());
    EXPECT_EQ(c.version == reader::kFeatureMapEntropyVersion, c.payload.size() < m.payload.size());
  }
  Opened packed(sections_of(fabric, false)), coded(sections_of(fabric, true));
  ASSERT_TRUE(coded.status.ok());
  reader::FeatureMaps a, b;
  ASSERT_TRUE(reader::read_feature_maps(packed.asset, &a).ok());
  ASSERT_TRUE(reader::read_feature_maps(coded.asset, &b).ok());
  expect_same_maps(a, b);
}

// The coded gap section of the 64^2 test fabric, for the damage tests (smaller tiles stay version
// 2: the tables would cost more than the coding saves).
Section coded_gap(const Fabric& fabric) {
  for (auto& m : feature_map_sections(fabric.maps))
    if (m.type == SectionType::GapMap) return compress::entropy_code_map(m);
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
  auto sections = sections_of(fabric, true);
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
    // How tests/fuzz/corpus/map_entropy.cbk was made: the 64^2 fabric with entropy-coded maps.
    const auto bytes = formats::serialize_asset(sections_of(fabric, true));
    std::ofstream(std::string(dir) + "/map_entropy.cbk", std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  ASSERT_EQ(good.version, reader::kFeatureMapEntropyVersion);
  const std::size_t offsets = reader::kMapEntropyHeaderBytes;
  const std::size_t tables = offsets + 8 * 3;  // P = 2
  const std::size_t blocks = tables + 2 * reader::kMapEntropyTableBytes;
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
    auto sections = sections_of(fabric, true);
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

// Deep validation: each defect is reported with its stable check ID.
#include <gtest/gtest.h>
#include <xxhash.h>

#include <algorithm>
#include <cstring>

#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"
#include "tests/support/fabric_asset_sections.hpp"

namespace {

using namespace clothbake;
using formats::Section;
using reader::SectionType;

// The fabric's records and coded maps (test_map_encoding.cpp plants hostile codes in the maps).
std::vector<Section> fabric_sections(const Fabric& fabric) {
  auto s = test_support::fabric_asset_sections(fabric);
  s.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  return s;
}

struct Findings {
  std::vector<std::string> ids;
  std::vector<std::string> messages;
  reader::ValidationSummary summary;
  bool has(const std::string& id) const {
    return std::find(ids.begin(), ids.end(), id) != ids.end();
  }
};

// Opens bytes (structure only) and validates them; a failing open is reported as a finding.
Findings validate(const std::vector<std::byte>& bytes) {
  std::vector<uint64_t> words((bytes.size() + 7) / 8);
  std::memcpy(words.data(), bytes.data(), bytes.size());
  Findings f;
  auto collect = [](void* user, reader::Check check, uint32_t, const char* message) {
    auto* findings = static_cast<Findings*>(user);
    findings->ids.push_back(reader::check_id(check));
    findings->messages.push_back(message);
  };
  reader::Asset asset;
  const reader::Status status = asset.open_memory(words.data(), bytes.size());
  f.summary = status.ok() ? reader::validate_asset(asset, collect, &f)
                          : reader::report_open_failure(status, collect, &f);
  return f;
}

// Offset of the payload of table entry `index`.
uint64_t payload_offset(const std::vector<std::byte>& bytes, uint32_t index) {
  uint64_t offset;
  std::memcpy(&offset, bytes.data() + 64 + 64 * index + 8, 8);
  return offset;
}

uint32_t index_of(const std::vector<Section>& sections, SectionType type) {
  const auto order = formats::table_order(sections);
  for (uint32_t i = 0; i < order.size(); ++i)
    if (order[i]->type == type) return i;
  return ~0u;
}

TEST(Validate, CleanAssetHasNoFindings) {
  const auto f =
      validate(formats::serialize_asset(fabric_sections(test_support::make_test_fabric(8))));
  EXPECT_EQ(f.summary.errors, 0u);
  EXPECT_EQ(f.summary.warnings, 0u);
}

TEST(Validate, EveryCorruptSectionIsNamed_E012) {
  const auto sections = fabric_sections(test_support::make_test_fabric(8));
  auto bytes = formats::serialize_asset(sections);
  const uint32_t height = index_of(sections, SectionType::HeightMap);
  const uint32_t albedo = index_of(sections, SectionType::AlbedoMap);
  bytes[payload_offset(bytes, height) + 5] ^= std::byte{1};
  bytes[payload_offset(bytes, albedo) + 9] ^= std::byte{1};
  const auto f = validate(bytes);
  EXPECT_EQ(std::count(f.ids.begin(), f.ids.end(), "CBK-E012"), 2);
  EXPECT_NE(f.messages[0].find("height"), std::string::npos) << f.messages[0];
}

TEST(Validate, NonZeroPadding_E013) {
  const auto sections = fabric_sections(test_support::make_test_fabric(5));
  auto bytes = formats::serialize_asset(sections);
  // The first section whose payload is not a multiple of 64 bytes: a byte of its padding.
  const auto order = formats::table_order(sections);
  uint32_t padded = ~0u;
  for (uint32_t i = 0; i < order.size() && padded == ~0u; ++i)
    if (order[i]->payload.size() % 64 != 0) padded = i;
  ASSERT_NE(padded, ~0u);
  bytes[payload_offset(bytes, padded) + order[padded]->payload.size()] = std::byte{7};
  EXPECT_TRUE(validate(bytes).has("CBK-E013"));
}

TEST(Validate, YarnIdWithoutMaterial_E018) {
  Fabric fabric = test_support::make_test_fabric(8);
  fabric.maps.yarn_id[8 * 3 + 5] = 2;
  const auto f = validate(formats::serialize_asset(fabric_sections(fabric)));
  ASSERT_TRUE(f.has("CBK-E018"));
  EXPECT_NE(f.messages[0].find("x=5, y=3"), std::string::npos) << f.messages[0];
}

TEST(Validate, ValueRanges_E021) {
  // (The maps' 16-bit codes cannot hold a gap beyond [0, 1] or a non-unit vector, so CBK-W004
  // has nothing to find in a 2.0 map; test_map_encoding.cpp plants the codes that remain wrong.)
  Fabric fabric = test_support::make_test_fabric(8);
  fabric.yarns[0].roughness = 0.0;
  auto f = validate(formats::serialize_asset(fabric_sections(fabric)));
  ASSERT_TRUE(f.has("CBK-E021"));
  EXPECT_NE(f.messages[0].find("roughness"), std::string::npos) << f.messages[0];
  fabric = test_support::make_test_fabric(8);
  fabric.maps.normal[4] = {0.f, 0.6f, -0.8f};  // below the horizon
  f = validate(formats::serialize_asset(fabric_sections(fabric)));
  ASSERT_TRUE(f.has("CBK-E021"));
  EXPECT_NE(f.messages[0].find("normal map: 1 texels have z <= 0 (first at x=4, y=0)"),
            std::string::npos)
      << f.messages[0];
}

TEST(Validate, MissingSections_E019) {
  std::vector<Section> no_gap, no_metadata;
  for (auto& s : fabric_sections(test_support::make_test_fabric(8))) {
    if (s.type != SectionType::GapMap) no_gap.push_back(s);
    if (s.type != SectionType::Metadata) no_metadata.push_back(s);
  }
  const auto f = validate(formats::serialize_asset(no_gap));
  ASSERT_TRUE(f.has("CBK-E019"));
  EXPECT_NE(f.messages[0].find("gap"), std::string::npos) << f.messages[0];
  EXPECT_TRUE(validate(formats::serialize_asset(no_metadata)).has("CBK-E019"));
}

TEST(Validate, MapsOfDifferentSizes_E016) {
  auto sections = fabric_sections(test_support::make_test_fabric(8));
  const Fabric small = test_support::make_test_fabric(4);
  for (auto& s : sections)
    if (s.type == SectionType::GapMap)
      for (auto& t : compress::feature_map_sections(small.maps))
        if (t.type == SectionType::GapMap) s = t;
  EXPECT_TRUE(validate(formats::serialize_asset(sections)).has("CBK-E016"));
}

TEST(Validate, WrongLayoutOfAKnownSection_E015) {
  auto sections = fabric_sections(test_support::make_test_fabric(8));
  for (auto& s : sections)
    if (s.type == SectionType::HeightMap)
      s = formats::make_array_section<double>(SectionType::HeightMap, 0,
                                              std::vector<double>(64, 0.0), {8, 8});
  EXPECT_TRUE(validate(formats::serialize_asset(sections)).has("CBK-E015"));
  sections = fabric_sections(test_support::make_test_fabric(8));
  for (auto& s : sections)
    if (s.type == SectionType::YarnMaterials) s.version = 7;
  EXPECT_TRUE(validate(formats::serialize_asset(sections)).has("CBK-E015"));
}

TEST(Validate, MetadataMustBeUtf8Json_E020) {
  auto sections = fabric_sections(test_support::make_test_fabric(4));
  for (auto& s : sections)
    if (s.type == SectionType::Metadata) {
      const std::string text = "{\"a\": \"\xc0\xaf\"}";  // overlong encoding of '/'
      s = formats::make_array_section<uint8_t>(
          SectionType::Metadata, 0,
          std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()),
          {uint32_t(text.size())});
    }
  EXPECT_TRUE(validate(formats::serialize_asset(sections)).has("CBK-E020"));
}

TEST(Validate, NanFromAForeignWriter_E017) {
  auto sections = fabric_sections(test_support::make_test_fabric(4));
  sections.push_back(formats::make_array_section<float>(SectionType::AsgFitError, 0,
                                                        std::vector<float>(16, 0.25f), {4, 4}));
  auto bytes = formats::serialize_asset(sections);
  // Write a NaN into the f32 fit-error map and fix its checksum and the header checksum, as a
  // foreign writer without the NaN check would.
  const uint32_t height = index_of(sections, SectionType::AsgFitError);
  const uint64_t offset = payload_offset(bytes, height);
  const uint32_t nan_bits = 0x7fc00000u;
  std::memcpy(bytes.data() + offset + 4 * 6, &nan_bits, 4);
  const uint64_t sum = XXH64(bytes.data() + offset, 64, 0);
  std::memcpy(bytes.data() + 64 + 64 * height + 24, &sum, 8);
  uint32_t count;
  std::memcpy(&count, bytes.data() + 12, 4);
  XXH64_state_t* st = XXH64_createState();
  XXH64_reset(st, 0);
  XXH64_update(st, bytes.data(), 56);
  XXH64_update(st, bytes.data() + 64, 64 * std::size_t(count));
  const uint64_t header_sum = XXH64_digest(st);
  XXH64_freeState(st);
  std::memcpy(bytes.data() + 56, &header_sum, 8);
  const auto f = validate(bytes);
  ASSERT_TRUE(f.has("CBK-E017"));
  EXPECT_NE(f.messages[0].find("element 6"), std::string::npos) << f.messages[0];
}

TEST(Validate, OpenFailuresCarryTheirIds) {
  auto bytes = formats::serialize_asset(fabric_sections(test_support::make_test_fabric(4)));
  auto truncated = bytes;
  truncated.resize(bytes.size() - 64);
  EXPECT_TRUE(validate(truncated).has("CBK-E002"));
  auto trailing = bytes;
  trailing.resize(bytes.size() + 64);
  EXPECT_TRUE(validate(trailing).has("CBK-E006"));
  // A flip in a header field open() does not interpret (the flags) opens; only the header
  // checksum, which validation verifies, sees it.
  auto header = bytes;
  header[20] ^= std::byte{1};
  EXPECT_TRUE(validate(header).has("CBK-E004"));
}

TEST(CheckIds, AreStable) {
  EXPECT_STREQ(reader::check_id(reader::Check::SectionChecksum), "CBK-E012");
  EXPECT_STREQ(reader::check_id(reader::Check::NotAnAsset), "CBK-E001");
  EXPECT_STREQ(reader::check_id(reader::Check::UnknownSection), "CBK-W001");
  EXPECT_STREQ(reader::check_id(reader::Check::NewerSectionVersion), "CBK-W005");
  EXPECT_STREQ(reader::check_id(reader::Check::None), "");
}

}  // namespace

// Writer -> reader round trips: every element type, every section type of this issue, the
// reserved types as generic typed arrays, the documented layout rules, and version handling.
#include <gtest/gtest.h>
#include <xxhash.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>

#include "common/error.hpp"
#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"
#include "tests/support/fabric_asset_sections.hpp"

namespace {

using namespace clothbake;
using formats::Section;
using reader::ElementType;
using reader::SectionType;

// Opens serialized bytes (kept alive by the fixture) from an 8-aligned copy and verifies every
// checksum.
struct Opened {
  std::vector<uint64_t> words;
  reader::Asset asset;
  reader::Status status;
  explicit Opened(const std::vector<std::byte>& bytes) : words((bytes.size() + 7) / 8) {
    std::memcpy(words.data(), bytes.data(), bytes.size());
    status = asset.open_memory(words.data(), bytes.size());
    if (status.ok()) status = reader::verify_checksums(asset);  // the writer's checksums hold
  }
};

Section metadata() {
  return formats::make_metadata_section({{"format", "clothbake-asset"}});
}

template <class T>
void expect_array_round_trip(std::vector<T> values, std::vector<uint32_t> dims) {
  std::vector<Section> sections{metadata()};
  sections.push_back(formats::make_array_section<T>(SectionType(0x8001), 7, values, dims));
  Opened opened(formats::serialize_asset(sections));
  ASSERT_TRUE(opened.status.ok()) << opened.status.message();
  reader::ArrayView<T> view;
  const reader::Status status = opened.asset.array(SectionType(0x8001), 7, &view);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(view.size, values.size());
  ASSERT_EQ(view.rank, dims.size());
  for (std::size_t d = 0; d < dims.size(); ++d)
    EXPECT_EQ(view.dims[d], dims[d]);
  const auto* base = opened.asset.bytes();
  EXPECT_EQ((reinterpret_cast<const unsigned char*>(view.data) - base) % 64, 0) << "payload offset";
  EXPECT_EQ(0, std::memcmp(view.data, values.data(), values.size() * sizeof(T)));
  // Asking for another element type is refused.
  reader::ArrayView<std::conditional_t<std::is_same_v<T, int8_t>, uint8_t, int8_t>> wrong;
  EXPECT_EQ(opened.asset.array(SectionType(0x8001), 7, &wrong).code(),
            reader::ErrorCode::WrongType);
}

template <class T>
std::vector<T> iota_values(std::size_t n, T start) {
  std::vector<T> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = T(start + T(i));
  return v;
}

TEST(RoundTrip, EveryElementType) {
  expect_array_round_trip<uint8_t>(iota_values<uint8_t>(70, 3), {70});
  expect_array_round_trip<int8_t>(iota_values<int8_t>(6, -3), {2, 3});
  expect_array_round_trip<uint16_t>(iota_values<uint16_t>(24, 65000), {2, 3, 4});
  expect_array_round_trip<int16_t>(iota_values<int16_t>(24, -12), {1, 2, 3, 4});
  expect_array_round_trip<uint32_t>({0u, 1u, 4000000000u}, {3});
  expect_array_round_trip<int32_t>({-2147483647 - 1, 0, 2147483647}, {3, 1});
  expect_array_round_trip<uint64_t>({0ull, ~0ull}, {2});
  expect_array_round_trip<int64_t>({std::numeric_limits<int64_t>::min(), 5}, {1, 2});
  expect_array_round_trip<float>({0.f, -1.5f, 3.25e-20f, std::numeric_limits<float>::denorm_min()},
                                 {2, 2});
  expect_array_round_trip<double>({1.0 / 3.0, -0.0, 1e300}, {3});
  expect_array_round_trip<reader::Half>({{0x3c00}, {0xc000}, {0x0001}}, {3});
}

TEST(RoundTrip, HalfToFloatIsExactForEveryFiniteHalf) {
  // Closed form: value = (-1)^s * 2^(e-15) * (1 + m/1024), subnormals 2^-14 * m/1024.
  for (uint32_t bits = 0; bits < 0x10000; ++bits) {
    const uint32_t e = (bits >> 10) & 0x1f, m = bits & 0x3ff;
    const double sign = (bits & 0x8000) ? -1.0 : 1.0;
    const float got = reader::half_to_float({uint16_t(bits)});
    if (e == 0x1f) {
      EXPECT_TRUE(m ? std::isnan(got) : std::isinf(got)) << bits;
      continue;
    }
    const double expected =
        e ? sign * std::ldexp(1.0 + m / 1024.0, int(e) - 15) : sign * std::ldexp(m / 1024.0, -14);
    ASSERT_EQ(double(got), expected) << "bits " << bits;
    ASSERT_EQ(std::signbit(got), sign < 0) << bits;
  }
}

TEST(RoundTrip, FabricSections) {
  // The test fabric's values are codes (6/64 heights, axes, 0, 1 and halves would be within the
  // unorm bound): compare within the codes' bounds.
  const Fabric fabric = test_support::make_test_fabric(16);
  std::vector<Section> sections = test_support::fabric_asset_sections(fabric);
  sections.push_back(metadata());
  Opened opened(formats::serialize_asset(sections));
  ASSERT_TRUE(opened.status.ok()) << opened.status.message();
  reader::FeatureMaps maps;
  ASSERT_TRUE(reader::read_feature_maps(opened.asset, &maps).ok());
  ASSERT_EQ(maps.resolution, 16u);
  for (std::size_t t = 0; t < fabric.maps.texel_count(); ++t) {
    ASSERT_LE(std::fabs(maps.height[t] - fabric.maps.height[t]),
              std::ldexp(std::fabs(fabric.maps.height[t]), -11));
    ASSERT_NEAR(maps.gap[t], fabric.maps.gap[t], 1.0 / 131070 + 1e-7);
    ASSERT_EQ(maps.yarn_id[t], fabric.maps.yarn_id[t]);
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(maps.tangent[3 * t + c], fabric.maps.tangent[t][c], 5e-5);
      ASSERT_NEAR(maps.normal[3 * t + c], fabric.maps.normal[t][c], 5e-5);
      ASSERT_NEAR(maps.albedo[3 * t + c], fabric.maps.albedo[t][c], 1.0 / 131070 + 1e-7);
    }
  }
  const reader::FabricInfoRecord* info;
  ASSERT_TRUE(reader::read_fabric_info(opened.asset, &info).ok());
  EXPECT_EQ(info->resolution, 16u);
  EXPECT_EQ(info->yarn_count, 2u);
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(info->sheen_color[c], fabric.sheen.color[c]);
  reader::ArrayView<reader::YarnMaterialRecord> yarns;
  ASSERT_TRUE(reader::read_yarn_materials(opened.asset, &yarns).ok());
  ASSERT_EQ(yarns.size, 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const YarnMaterial& y = fabric.yarns[i];
    EXPECT_EQ(std::string(yarns[i].name), y.name);
    EXPECT_EQ(yarns[i].roughness, y.roughness);
    EXPECT_EQ(yarns[i].optical_thickness, y.optical_thickness);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(yarns[i].specular_albedo[c], y.specular_albedo[c]);
      EXPECT_EQ(yarns[i].diffuse_reflectance[c], y.diffuse_reflectance[c]);
      EXPECT_EQ(yarns[i].diffuse_transmittance[c], y.diffuse_transmittance[c]);
      EXPECT_EQ(yarns[i].color[c], y.color[c]);
    }
  }
  const auto summary = reader::validate_asset(opened.asset, nullptr, nullptr);
  EXPECT_EQ(summary.errors, 0u);
  EXPECT_EQ(summary.warnings, 0u);
}

TEST(RoundTrip, MetadataIsSortedJson) {
  nlohmann::json j = {{"zeta", 1}, {"alpha", {{"b", 2}, {"a", "\xc3\xa9"}}}};
  std::vector<Section> sections{formats::make_metadata_section(j)};
  Opened opened(formats::serialize_asset(sections));
  ASSERT_TRUE(opened.status.ok());
  std::string_view text;
  ASSERT_TRUE(opened.asset.metadata_json(&text).ok());
  EXPECT_EQ(nlohmann::json::parse(text), j);
  EXPECT_LT(text.find("alpha"), text.find("zeta"));
}

TEST(RoundTrip, ReservedSectionTypesAsTypedArrays) {
  // Later stages store their tables as typed arrays of these reserved types.
  const SectionType reserved[] = {
      SectionType::ParallaxTable,     SectionType::ParallaxSat,
      SectionType::VisibilityAsg,     SectionType::AsgFitError,
      SectionType::ClusterLabels,     SectionType::ClusterMeanVisibility,
      SectionType::RadianceRawTables, SectionType::RadianceCompressedTables};
  std::vector<Section> sections{metadata()};
  uint32_t k = 0;
  for (SectionType type : reserved) {
    const auto values = iota_values<float>(2 * 3 * 5, float(k));
    for (uint32_t instance = 0; instance < 3; ++instance)
      sections.push_back(formats::make_array_section<float>(type, instance, values, {2, 3, 5}));
    ++k;
  }
  Opened opened(formats::serialize_asset(sections));
  ASSERT_TRUE(opened.status.ok()) << opened.status.message();
  EXPECT_EQ(opened.asset.section_count(), 1u + 3u * 8u);
  k = 0;
  for (SectionType type : reserved) {
    ASSERT_NE(reader::section_type_name(type), nullptr);
    SectionType parsed;
    ASSERT_TRUE(reader::section_type_from_name(reader::section_type_name(type), &parsed));
    EXPECT_EQ(parsed, type);
    for (uint32_t instance = 0; instance < 3; ++instance) {
      reader::ArrayView<float> view;
      ASSERT_TRUE(opened.asset.array(type, instance, &view).ok());
      ASSERT_EQ(view.size, 30u);
      EXPECT_EQ(view[29], float(k) + 29.f);
    }
    reader::ArrayView<float> view;
    EXPECT_EQ(opened.asset.array(type, 3, &view).code(), reader::ErrorCode::NotFound);
    ++k;
  }
}

TEST(RoundTrip, LayoutFollowsTheSpecification) {
  const Fabric fabric = test_support::make_test_fabric(5);  // odd sizes: payloads need padding
  std::vector<Section> sections = compress::feature_map_sections(fabric.maps);
  sections.push_back(metadata());
  std::reverse(sections.begin(), sections.end());
  const auto bytes = formats::serialize_asset(sections);
  EXPECT_EQ(bytes.size() % 64, 0u);
  EXPECT_EQ(bytes.size(), formats::asset_size(sections));
  Opened opened(bytes);
  ASSERT_TRUE(opened.status.ok()) << opened.status.message();
  // Table sorted by (type, instance), payloads 64-aligned and in table order, padding zero.
  uint64_t previous_end = 64 + 64 * uint64_t(opened.asset.section_count());
  uint32_t previous_type = 0;
  for (uint32_t i = 0; i < opened.asset.section_count(); ++i) {
    reader::SectionInfo s;
    ASSERT_TRUE(opened.asset.section(i, &s).ok());
    EXPECT_GT(uint32_t(s.type), previous_type);
    previous_type = uint32_t(s.type);
    EXPECT_EQ(s.offset % 64, 0u);
    EXPECT_GE(s.offset, previous_end);
    EXPECT_LT(s.offset - previous_end, 64u);
    for (uint64_t b = previous_end; b < s.offset; ++b)
      EXPECT_EQ(bytes[b], std::byte{0});
    EXPECT_EQ(s.checksum, XXH64(s.data, s.stored_size, 0));
    previous_end = s.offset + s.stored_size;
  }
  // The header checksum is XXH64 of bytes [0, 56) and the table.
  XXH64_state_t* st = XXH64_createState();
  XXH64_reset(st, 0);
  XXH64_update(st, bytes.data(), 56);
  XXH64_update(st, bytes.data() + 64, 64 * opened.asset.section_count());
  EXPECT_EQ(XXH64_digest(st), opened.asset.content_hash());
  XXH64_freeState(st);
}

TEST(RoundTrip, SameSectionsGiveSameBytesWhateverTheOrder) {
  const Fabric fabric = test_support::make_test_fabric(8);
  std::vector<Section> a = compress::feature_map_sections(fabric.maps);
  a.push_back(metadata());
  std::vector<Section> b = a;
  std::reverse(b.begin(), b.end());
  EXPECT_EQ(formats::serialize_asset(a), formats::serialize_asset(b));
}

// A section whose bytes are held elsewhere (Section::mapped, as the stage cache hands them out)
// is written exactly like the same section owning them; having both forms at once is refused.
TEST(RoundTrip, MappedPayloadsGiveTheOwnedBytes) {
  const Fabric fabric = test_support::make_test_fabric(8);
  std::vector<Section> owned = compress::feature_map_sections(fabric.maps);
  owned.push_back(metadata());
  std::vector<Section> mapped = owned;
  auto keep = std::make_shared<std::vector<std::vector<std::byte>>>();
  for (Section& s : mapped) {
    keep->push_back(std::move(s.payload));
    s.payload.clear();
    s.mapped = keep->back();
    s.mapped_owner = keep;
  }
  EXPECT_EQ(formats::serialize_asset(owned), formats::serialize_asset(mapped));
  EXPECT_EQ(formats::asset_size(owned), formats::asset_size(mapped));
  mapped[0].payload = owned[0].payload;
  EXPECT_THROW(formats::serialize_asset(mapped), Error);
}

// Patches the header (minor or major version) and fixes the header checksum.
void patch_header(std::vector<std::byte>& bytes, std::size_t offset, uint16_t value) {
  std::memcpy(bytes.data() + offset, &value, 2);
  uint32_t count;
  std::memcpy(&count, bytes.data() + 12, 4);
  XXH64_state_t* st = XXH64_createState();
  XXH64_reset(st, 0);
  XXH64_update(st, bytes.data(), 56);
  XXH64_update(st, bytes.data() + 64, 64 * std::size_t(count));
  const uint64_t sum = XXH64_digest(st);
  XXH64_freeState(st);
  std::memcpy(bytes.data() + 56, &sum, 8);
}

TEST(Versions, NewerMajorIsRefusedNamingTheSideToRebuild) {
  auto bytes = formats::serialize_asset(std::vector<Section>{metadata()});
  patch_header(bytes, 8, 3);
  Opened newer(bytes);
  ASSERT_EQ(newer.status.code(), reader::ErrorCode::UnsupportedVersion);
  EXPECT_STREQ(newer.status.check_id(), "CBK-E003");
  EXPECT_NE(std::string(newer.status.message()).find("format 3.0"), std::string::npos);
  EXPECT_NE(std::string(newer.status.message()).find("rebuild the reader"), std::string::npos);
  for (uint16_t older_major : {0, 1}) {
    patch_header(bytes, 8, older_major);
    Opened older(bytes);
    ASSERT_EQ(older.status.code(), reader::ErrorCode::UnsupportedVersion);
    EXPECT_NE(std::string(older.status.message()).find("re-bake"), std::string::npos);
  }
}

TEST(Versions, NewerMinorIsReadAndUnknownSectionsSkipped) {
  std::vector<Section> sections{metadata()};
  sections.push_back(formats::make_array_section<float>(SectionType(0x0777), 0,
                                                        std::vector<float>{1.f, 2.f}, {2}));
  auto bytes = formats::serialize_asset(sections);
  // A newer minor may use a codec and an element type this reader does not know: patch the
  // unknown section's entry (#1, after metadata) to codec 9, element type 99.
  const std::size_t entry = 64 + 64 * 1;
  const uint16_t codec = 9, element = 99;
  std::memcpy(bytes.data() + entry + 6, &codec, 2);
  std::memcpy(bytes.data() + entry + 40, &element, 2);
  patch_header(bytes, 10, reader::kFormatMinor + 1);  // newer than this reader (2.1)
  Opened opened(bytes);
  ASSERT_TRUE(opened.status.ok()) << opened.status.message();
  EXPECT_EQ(opened.asset.version_minor(), reader::kFormatMinor + 1);
  std::string_view json;
  EXPECT_TRUE(opened.asset.metadata_json(&json).ok());
  reader::ArrayView<float> view;
  EXPECT_EQ(opened.asset.array(SectionType(0x0777), 0, &view).code(),
            reader::ErrorCode::Unsupported);
  std::vector<std::string> ids;
  auto collect = [](void* user, reader::Check check, uint32_t, const char*) {
    static_cast<std::vector<std::string>*>(user)->push_back(reader::check_id(check));
  };
  const auto summary = reader::validate_asset(opened.asset, collect, &ids);
  EXPECT_EQ(summary.errors, 0u);
  EXPECT_NE(std::find(ids.begin(), ids.end(), "CBK-W002"), ids.end());
  EXPECT_NE(std::find(ids.begin(), ids.end(), "CBK-W001"), ids.end());
  // The same file claiming minor 0 is malformed: 2.0 defines no codec 9.
  patch_header(bytes, 10, 0);
  Opened current(bytes);
  EXPECT_EQ(current.status.code(), reader::ErrorCode::Malformed);
}

TEST(Writer, RefusesNanAndInfNamingSectionAndElement) {
  std::vector<float> values(12, 1.f);
  values[7] = std::numeric_limits<float>::quiet_NaN();
  try {
    formats::make_array_section<float>(SectionType::HeightMap, 0, values, {3, 4});
    FAIL() << "NaN accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("height element 7 [1, 3] is NaN"), std::string::npos)
        << e.what();
  }
  std::vector<double> doubles{1.0, -std::numeric_limits<double>::infinity()};
  try {
    formats::make_array_section<double>(SectionType(0x8002), 4, doubles, {2});
    FAIL() << "Inf accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("type 0x8002 instance 4 element 1 [1] is Inf"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(formats::make_array_section<reader::Half>(SectionType(0x8002), 0,
                                                         std::vector<reader::Half>{{0x7c00}}, {1}),
               Error);
  Fabric fabric = test_support::make_test_fabric(4);
  fabric.maps.normal[6][2] = std::numeric_limits<float>::infinity();
  try {
    feature_map_codes(fabric.maps);
    FAIL() << "Inf normal accepted";
  } catch (const Error& e) {
    // Texel x=2, y=1, channel z.
    EXPECT_NE(std::string(e.what()).find("normal element 20 [1, 2, 2] is Inf"), std::string::npos)
        << e.what();
  }
  fabric = test_support::make_test_fabric(4);
  fabric.yarns[1].roughness = std::nan("");
  EXPECT_THROW(fabric_record_sections(fabric), Error);
}

TEST(Writer, RejectsInconsistentSections) {
  Section bad =
      formats::make_array_section<float>(SectionType(0x8003), 0, std::vector<float>{1.f, 2.f}, {2});
  bad.dims = {3};
  EXPECT_THROW(formats::serialize_asset(std::vector<Section>{bad}), Error);
  Section a = metadata(), b = metadata();
  EXPECT_THROW(formats::serialize_asset(std::vector<Section>{a, b}), Error);
  Fabric fabric = test_support::make_test_fabric(4);
  fabric.maps.gap.pop_back();
  try {
    feature_map_codes(fabric.maps);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'gap' has 15 texels, expected 16"), std::string::npos);
  }
}

TEST(Writer, LongYarnNamesAreCutAtACharacterBoundary) {
  Fabric fabric = test_support::make_test_fabric(4);
  fabric.yarns[0].name = std::string(29, 'a') + "\xc3\xa9\xc3\xa9";  // 29 + 2 + 2 bytes
  std::vector<Section> sections = fabric_record_sections(fabric);
  sections.push_back(metadata());
  Opened opened(formats::serialize_asset(sections));
  reader::ArrayView<reader::YarnMaterialRecord> yarns;
  ASSERT_TRUE(reader::read_yarn_materials(opened.asset, &yarns).ok());
  EXPECT_EQ(std::string(yarns[0].name), std::string(29, 'a') + "\xc3\xa9");
}

}  // namespace

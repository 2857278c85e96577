// Golden bytes: the writer must reproduce tests/formats/data/golden_v2.cbk exactly, the reader
// must read the checked-in file (independently of today's writer) to the known values, and it must
// refuse the format-1.0 file of the same fabric with a message that says to re-bake it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/validate/validate.hpp"
#include "tests/formats/golden_asset.hpp"

namespace {

using namespace clothbake;

std::vector<std::byte> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> bytes(chars.size());
  if (!chars.empty()) std::memcpy(bytes.data(), chars.data(), chars.size());
  return bytes;
}

TEST(Golden, WriterReproducesTheCheckedInBytes) {
  const std::vector<std::byte> bytes = formats::serialize_asset(test_support::golden_sections());
  const std::string path = test_support::golden_path();
  if (std::getenv("CLOTHBAKE_REGENERATE_GOLDEN")) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    ASSERT_TRUE(out.good());
    GTEST_SKIP() << "regenerated " << path;
  }
  const std::vector<std::byte> golden = read_file(path);
  ASSERT_FALSE(golden.empty()) << "missing " << path;
  ASSERT_EQ(bytes.size(), golden.size());
  for (std::size_t i = 0; i < bytes.size(); ++i)
    ASSERT_EQ(bytes[i], golden[i]) << "first difference at byte " << i;
}

TEST(Golden, AFormat1AssetIsRefusedWithARebakeMessage) {
  reader::Asset asset;
  const reader::Status status = asset.open_file(test_support::golden_v1_path().c_str());
  EXPECT_EQ(status.code(), reader::ErrorCode::UnsupportedVersion);
  EXPECT_STREQ(status.check_id(), "CBK-E003");
  const std::string message = status.message();
  EXPECT_NE(message.find("asset format 1.0, this reader reads format 2.x"), std::string::npos)
      << message;
  EXPECT_NE(message.find("re-bake it"), std::string::npos) << message;
  EXPECT_NE(message.find("clothbake bake"), std::string::npos) << message;
}

TEST(Golden, ReaderReadsTheCheckedInFile) {
  reader::Asset asset;
  reader::Status status = asset.open_file(test_support::golden_path().c_str());
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(asset.version_major(), 2);
  EXPECT_EQ(asset.version_minor(), 0);
  EXPECT_EQ(asset.file_size() % 64, 0u);
  EXPECT_EQ(asset.section_count(), 9u);
  reader::SectionInfo s;
  ASSERT_TRUE(asset.find(reader::SectionType::TangentMap, 0, &s).ok());
  EXPECT_EQ(s.version, 1);
  EXPECT_EQ(s.element_type, reader::ElementType::U8);
  ASSERT_TRUE(asset.find(reader::SectionType::YarnIdMap, 0, &s).ok());
  EXPECT_EQ(s.element_type, reader::ElementType::U16);

  const reader::FabricInfoRecord* info = nullptr;
  ASSERT_TRUE(reader::read_fabric_info(asset, &info).ok());
  EXPECT_EQ(info->resolution, 4u);
  EXPECT_EQ(info->yarn_count, 2u);
  EXPECT_EQ(info->sheen_color[1], 0.25);
  EXPECT_EQ(info->sheen_roughness, 0.5);

  reader::ArrayView<reader::YarnMaterialRecord> yarns;
  ASSERT_TRUE(reader::read_yarn_materials(asset, &yarns).ok());
  ASSERT_EQ(yarns.size, 2u);
  EXPECT_STREQ(yarns[0].name, "warp");
  EXPECT_STREQ(yarns[1].name, "weft");
  EXPECT_EQ(yarns[1].optical_thickness, 4.0);
  EXPECT_EQ(yarns[0].roughness, 0.25);

  reader::FeatureMaps maps;
  status = reader::read_feature_maps(asset, &maps);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(maps.resolution, 4u);
  // The test fabric's values within the codes' bounds (exact where the value is a code: 6/64 in
  // f16, the axes, 0 and 1). Texel (x=1, y=2): (1/2 + 2/2) = 1 is odd -> weft; height
  // (3 + 10) % 7 / 64.
  const Fabric fabric = test_support::make_test_fabric(4, "golden");
  const std::size_t t = 2 * 4 + 1;
  EXPECT_EQ(maps.height[t], 6.f / 64.f);
  EXPECT_EQ(maps.yarn_id[t], 1);
  EXPECT_EQ(maps.tangent[3 * t + 0], 1.f);
  EXPECT_NEAR(maps.normal[3 * t + 1], -0.6f, 5e-5);
  EXPECT_NEAR(maps.albedo[3 * t + 2], 0.5f, 1.0 / 131070 + 1e-7);
  EXPECT_EQ(maps.gap[3 * 4 + 3], 0.f);
  EXPECT_EQ(maps.gap[0], 1.f);
  for (std::size_t i = 0; i < 16; ++i) {
    const auto& m = fabric.maps;
    EXPECT_EQ(maps.yarn_id[i], m.yarn_id[i]);
    EXPECT_LE(std::fabs(maps.height[i] - m.height[i]), std::ldexp(std::fabs(m.height[i]), -11));
    EXPECT_LE(std::fabs(maps.gap[i] - m.gap[i]), 1.0 / 131070 + 1e-7);
    for (int c = 0; c < 3; ++c) {
      EXPECT_LE(std::fabs(maps.albedo[3 * i + c] - m.albedo[i][c]), 1.0 / 131070 + 1e-7);
      EXPECT_NEAR(maps.tangent[3 * i + c], m.tangent[i][c], 5e-5);
      EXPECT_NEAR(maps.normal[3 * i + c], m.normal[i][c], 5e-5);
    }
  }

  std::string_view json;
  ASSERT_TRUE(asset.metadata_json(&json).ok());
  EXPECT_NE(json.find("\"golden\""), std::string_view::npos);

  const auto summary = reader::validate_asset(asset, nullptr, nullptr);
  EXPECT_EQ(summary.errors, 0u);
  EXPECT_EQ(summary.warnings, 0u);
}

}  // namespace

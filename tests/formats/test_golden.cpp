// Golden bytes: the writer must reproduce tests/formats/data/golden_v1.cbk exactly, and the reader
// must read the checked-in file (independently of today's writer) to the known values.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/validate.hpp"
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
  if (std::getenv("CLOTHBAKE_REGENERATE_GOLDEN")) {
    std::ofstream out(test_support::golden_path(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    ASSERT_TRUE(out.good());
    GTEST_SKIP() << "regenerated " << test_support::golden_path();
  }
  const std::vector<std::byte> golden = read_file(test_support::golden_path());
  ASSERT_FALSE(golden.empty()) << "missing " << test_support::golden_path();
  ASSERT_EQ(bytes.size(), golden.size());
  for (std::size_t i = 0; i < bytes.size(); ++i)
    ASSERT_EQ(bytes[i], golden[i]) << "first difference at byte " << i;
}

TEST(Golden, ReaderReadsTheCheckedInFile) {
  reader::Asset asset;
  reader::Status status = asset.open_file(test_support::golden_path().c_str());
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(asset.version_major(), 1);
  EXPECT_EQ(asset.version_minor(), 0);
  EXPECT_EQ(asset.file_size() % 64, 0u);
  EXPECT_EQ(asset.section_count(), 9u);

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

  reader::FeatureMapsView maps;
  status = reader::read_feature_maps(asset, &maps);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(maps.resolution, 4u);
  // Texel (x=1, y=2): (1/2 + 2/2) = 1 is odd -> weft; height (3 + 10) % 7 / 64.
  const std::size_t t = 2 * 4 + 1;
  EXPECT_EQ(maps.height[t], 6.f / 64.f);
  EXPECT_EQ(maps.yarn_id[t], 1);
  EXPECT_EQ(maps.tangent[3 * t + 0], 1.f);
  EXPECT_EQ(maps.normal[3 * t + 1], -0.6f);
  EXPECT_EQ(maps.albedo[3 * t + 2], 0.5f);
  EXPECT_EQ(maps.gap[3 * 4 + 3], 0.f);
  EXPECT_EQ(maps.gap[0], 1.f);

  std::string_view json;
  ASSERT_TRUE(asset.metadata_json(&json).ok());
  EXPECT_NE(json.find("\"golden\""), std::string_view::npos);

  const auto summary = reader::validate_asset(asset, nullptr, nullptr);
  EXPECT_EQ(summary.errors, 0u);
  EXPECT_EQ(summary.warnings, 0u);
}

}  // namespace

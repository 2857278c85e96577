// write_fabric_directory: the written fabric.toml loads back to the same maps and parameters
// (round trip), previews follow their conventions, and nothing is written when anything fails.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/fabric_write.hpp"
#include "common/diagnostics.hpp"
#include "tests/bake/inputs/test_support.hpp"

namespace clothbake {
namespace {

namespace fs = std::filesystem;
using testing::error_message;
using ::testing::HasSubstr;
using testing::ScratchDir;

void expect_same_fabric(const Fabric& a, const Fabric& b) {
  // Bit-identical maps: EXR float storage is exact and unit vectors are not re-normalised.
  EXPECT_EQ(a.maps.resolution, b.maps.resolution);
  EXPECT_EQ(a.maps.height, b.maps.height);
  EXPECT_EQ(a.maps.tangent, b.maps.tangent);
  EXPECT_EQ(a.maps.normal, b.maps.normal);
  EXPECT_EQ(a.maps.gap, b.maps.gap);
  EXPECT_EQ(a.maps.yarn_id, b.maps.yarn_id);
  EXPECT_EQ(a.maps.albedo, b.maps.albedo);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.tile_size_mm, b.tile_size_mm);
  ASSERT_EQ(a.yarns.size(), b.yarns.size());
  for (std::size_t i = 0; i < a.yarns.size(); ++i) {
    EXPECT_EQ(a.yarns[i].name, b.yarns[i].name);
    EXPECT_EQ(a.yarns[i].roughness, b.yarns[i].roughness);
    EXPECT_EQ(a.yarns[i].optical_thickness, b.yarns[i].optical_thickness);
    EXPECT_EQ(a.yarns[i].specular_albedo, b.yarns[i].specular_albedo);
    EXPECT_EQ(a.yarns[i].diffuse_reflectance, b.yarns[i].diffuse_reflectance);
    EXPECT_EQ(a.yarns[i].diffuse_transmittance, b.yarns[i].diffuse_transmittance);
    EXPECT_EQ(a.yarns[i].color, b.yarns[i].color);
  }
  EXPECT_EQ(a.sheen.color, b.sheen.color);
  EXPECT_EQ(a.sheen.roughness, b.sheen.roughness);
  const BakeSettings &x = a.bake, &y = b.bake;
  EXPECT_EQ(x.resolution, y.resolution);
  EXPECT_EQ(x.parallax_dirs, y.parallax_dirs);
  EXPECT_EQ(x.parallax_min_cos, y.parallax_min_cos);
  EXPECT_EQ(x.parallax_max_error, y.parallax_max_error);
  EXPECT_EQ(x.visibility_dirs, y.visibility_dirs);
  EXPECT_EQ(x.radiance_dirs, y.radiance_dirs);
  EXPECT_EQ(x.clusters, y.clusters);
  EXPECT_EQ(x.compress, y.compress);
  EXPECT_EQ(x.compress_clusters, y.compress_clusters);
  EXPECT_EQ(x.compress_rank, y.compress_rank);
  EXPECT_EQ(x.seed, y.seed);
}

class FabricWrite : public ::testing::Test {
 protected:
  void SetUp() override { set_quiet(true); }
  void TearDown() override {
    set_quiet(false);
    take_warnings();
  }
};

TEST_F(FabricWrite, RoundTripOfAnExampleWeave) {
  ScratchDir dir;
  LoadOptions options;
  options.resolution = 48;
  LoadedFabric original = load_fabric_description(
      std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/argyle.toml", options);
  auto files = write_fabric_directory(original.fabric, dir / "out", "test");
  EXPECT_EQ(files.size(), 13u);  // 6 EXR maps, 6 previews, fabric.toml
  for (const auto& f : files)
    EXPECT_TRUE(fs::exists(f.path)) << f.path;
  Fabric reloaded = load_fabric(dir / "out/fabric.toml");
  expect_same_fabric(original.fabric, reloaded);
  // Every map is now read from a file, with its hash.
  ASSERT_EQ(reloaded.inputs.size(), 7u);
  EXPECT_EQ(reloaded.inputs[6].role, "albedo");
}

TEST_F(FabricWrite, RoundTripWithNamesThatNeedQuoting) {
  ScratchDir dir;
  LoadedFabric original = fabric_from_named_weave("satin5", 20);
  original.fabric.name = "odd \"name\" \\ with\ttab";
  original.fabric.yarns[1].name = "weft \"b\"";
  original.fabric.yarns[0].roughness = 0.1 + 0.2;  // not exactly representable in short form
  original.fabric.sheen.color = {0.3, 1.0 / 3.0, 0.0};
  original.fabric.bake.seed = 1234567890123ull;
  original.fabric.bake.compress = false;
  write_fabric_directory(original.fabric, dir / "q", "");
  expect_same_fabric(original.fabric, load_fabric(dir / "q/fabric.toml"));
}

TEST_F(FabricWrite, RoundTripOfAnImageFabricWithoutPhysicalSize) {
  ScratchDir dir;
  auto f = testing::write_image_fabric(dir, 8);
  Fabric original = load_fabric(f.toml);
  write_fabric_directory(original, dir / "copy", "");
  Fabric reloaded = load_fabric(dir / "copy/fabric.toml");
  expect_same_fabric(original, reloaded);
  EXPECT_THAT(testing::read_text(dir / "copy/fabric.toml"), ::testing::Not(HasSubstr("[tile]")));
}

TEST_F(FabricWrite, PreviewConventions) {
  FabricMaps m;
  m.resolution = 2;
  m.height = {-1, 0, 1, 3};
  m.tangent = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.normal = m.tangent;
  m.gap = {0, 1, 1, 0};
  m.yarn_id = {0, 1, 0, 1};
  m.albedo = std::vector<Vec3f>(4, Vec3f{0.5f, 0.0f, 1.0f});
  Image h = preview_image(m, "height");
  EXPECT_EQ(h.pixels, (std::vector<float>{0.0f, 0.25f, 0.5f, 1.0f}));
  Image t = preview_image(m, "tangent");
  EXPECT_EQ(t.at(0, 0, 0), 1.0f);
  EXPECT_EQ(t.at(1, 0, 0), 0.0f);
  EXPECT_EQ(t.at(1, 0, 1), 0.5f);
  Image ids = preview_image(m, "yarn_id");
  EXPECT_NE(ids.at(0, 0, 0), ids.at(1, 0, 0));
  EXPECT_EQ(ids.at(0, 0, 1), ids.at(0, 1, 1));
  Image a = preview_image(m, "albedo");
  EXPECT_NEAR(a.at(0, 0, 0), 0.7354, 1e-3);  // sRGB encoding of linear 0.5
  // Distinct yarn colours for the first ids.
  for (unsigned i = 0; i < 8; ++i)
    for (unsigned j = 0; j < i; ++j)
      EXPECT_NE(yarn_id_color(i), yarn_id_color(j)) << i << " " << j;
}

TEST_F(FabricWrite, ExistingDirectoryKeepsUnrelatedFilesAndReplacesOutputs) {
  ScratchDir dir;
  fs::create_directories(dir / "out");
  testing::write_text(dir / "out/notes.txt", "keep me");
  testing::write_text(dir / "out/fabric.toml", "old");
  LoadedFabric loaded = fabric_from_named_weave("plain", 8);
  write_fabric_directory(loaded.fabric, dir / "out", "");
  EXPECT_EQ(testing::read_text(dir / "out/notes.txt"), "keep me");
  EXPECT_NE(testing::read_text(dir / "out/fabric.toml"), "old");
  // No temporary directory is left behind.
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename(), "out") << entry.path();
}

TEST_F(FabricWrite, TrailingSlashAndNestedNewDirectories) {
  ScratchDir dir;
  LoadedFabric loaded = fabric_from_named_weave("plain", 8);
  auto files = write_fabric_directory(loaded.fabric, dir / "x/y/out/", "");
  EXPECT_TRUE(fs::exists(dir / "x/y/out/fabric.toml"));
  EXPECT_EQ(files.back().path, dir / "x/y/out/fabric.toml");
  for (const char* bad : {"", ".", "./", "x/.."})
    EXPECT_THAT(error_message([&] { write_fabric_directory(loaded.fabric, bad, ""); }),
                HasSubstr("not a valid output directory name"))
        << bad;
}

TEST_F(FabricWrite, NothingIsWrittenOnFailure) {
  ScratchDir dir;
  LoadedFabric loaded = fabric_from_named_weave("plain", 8);
  // Inconsistent maps (a bug upstream): refused before anything is written.
  Fabric broken = loaded.fabric;
  broken.maps.gap.pop_back();
  error_message([&] { write_fabric_directory(broken, dir / "a/b/out", ""); }, ExitCode::Internal);
  EXPECT_FALSE(fs::exists(dir / "a")) << "no parent directories are left behind";
  // An output path that is a file.
  testing::write_text(dir / "file", "x");
  EXPECT_THAT(error_message([&] { write_fabric_directory(loaded.fabric, dir / "file", ""); }),
              HasSubstr("exists and is not a directory"));
  EXPECT_EQ(testing::read_text(dir / "file"), "x");
  // An unwritable parent (skipped when running as root, which can write anywhere).
  fs::create_directories(dir / "ro");
  fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
  if (::geteuid() != 0) {
    error_message([&] { write_fabric_directory(loaded.fabric, dir / "ro/out", ""); });
    EXPECT_FALSE(fs::exists(dir / "ro/out"));
  }
  fs::permissions(dir / "ro", fs::perms::owner_all);
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr(".tmp-")));
}

TEST(TomlQuote, EscapesWhatTomlRequires) {
  EXPECT_EQ(toml_quote("plain"), "\"plain\"");
  EXPECT_EQ(toml_quote("a\"b\\c\n"), "\"a\\\"b\\\\c\\n\"");
  EXPECT_EQ(toml_quote(std::string(1, '\x01')), "\"\\u0001\"");
}

}  // namespace
}  // namespace clothbake

// load_fabric: every bad input gets Error(Input) naming the file and the key, line or pixel; good
// inputs resolve defaults, units, relative paths and content hashes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/wif.hpp"
#include "common/diagnostics.hpp"
#include "tests/bake/inputs/test_support.hpp"

namespace clothbake {
namespace {

using testing::error_message;
using ::testing::HasSubstr;
using testing::make_image;
using testing::ScratchDir;
using testing::write_image_fabric;
using testing::write_text;

std::string load_error(const std::string& toml) {
  return error_message([&] { load_fabric(toml); });
}

class QuietTest : public ::testing::Test {
 protected:
  void SetUp() override {
    set_quiet(true);
    take_warnings();
  }
  void TearDown() override { set_quiet(false); }
};

using FabricLoad = QuietTest;

// An 8-bit height image in tile units without height_scale is a relief up to a tile side tall: a
// warning naming the file; with height_scale, or a float image, none.
TEST_F(FabricLoad, IntegerHeightInTileUnitsWithoutAScaleWarns) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  write_image(dir / "height8.png", make_image(8, 8, 1, [](int x, int, int) { return x / 7.0; }),
              PixelType::UInt8);
  write_text(f.toml, "name = \"h\"\n[maps]\nheight = \"height8.png\"\ntangent = \"tangent.exr\"\n");
  take_warnings();
  (void)load_fabric_description(f.toml);
  auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("height8.png"));
  EXPECT_THAT(warnings[0], HasSubstr("8-bit height image in tile units without height_scale"));
  write_text(f.toml,
             "name = \"h\"\n[maps]\nheight = \"height8.png\"\ntangent = "
             "\"tangent.exr\"\nheight_scale = 0.05\n");
  (void)load_fabric_description(f.toml);
  EXPECT_TRUE(take_warnings().empty());
  auto g = write_image_fabric(dir, 8);  // float heights
  (void)load_fabric_description(g.toml);
  EXPECT_TRUE(take_warnings().empty());
}

TEST_F(FabricLoad, ImageFabricWithDefaults) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  LoadedFabric loaded = load_fabric_description(f.toml);
  const Fabric& fabric = loaded.fabric;
  EXPECT_EQ(loaded.source, FabricSource::Images);
  EXPECT_EQ(fabric.name, "test fabric");
  EXPECT_EQ(fabric.maps.resolution, 8);
  EXPECT_EQ(fabric.bake.resolution, 8) << "bake.resolution defaults to the maps' size";
  EXPECT_EQ(fabric.tile_size_mm, 0.0);
  ASSERT_EQ(fabric.yarns.size(), 1u);
  EXPECT_EQ(fabric.yarns[0].name, "yarn");
  EXPECT_EQ(fabric.yarns[0].roughness, YarnMaterial{}.roughness);
  EXPECT_EQ(fabric.bake.clusters, 8);  // paper defaults
  // 0 = "auto": the compress stage picks the ranks for its target error (docs/fabric-format.md).
  EXPECT_EQ(fabric.bake.compress_clusters, 0);
  EXPECT_EQ(fabric.bake.compress_rank, 0);
  EXPECT_EQ(fabric.bake.radiance_dirs, 32);
  EXPECT_DOUBLE_EQ(fabric.bake.parallax_min_cos, 0.6);
  const std::size_t texels = 64;
  EXPECT_EQ(fabric.maps.height.size(), texels);
  EXPECT_EQ(fabric.maps.gap, std::vector<float>(texels, 1.0f));
  EXPECT_EQ(fabric.maps.yarn_id, std::vector<uint16_t>(texels, 0));
  EXPECT_EQ(fabric.maps.normal.size(), texels) << "normals are derived from the height map";
  for (const auto& a : fabric.maps.albedo)
    EXPECT_EQ(a, (Vec3f{1, 1, 1}));
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      ASSERT_NEAR(fabric.maps.height[fabric.maps.index(x, y)], testing::test_height(x, y, 8), 1e-7);
  // Inputs: the TOML first, then each image, each with its XXH64.
  ASSERT_EQ(fabric.inputs.size(), 3u);
  EXPECT_EQ(fabric.inputs[0].role, "fabric");
  EXPECT_EQ(fabric.inputs[0].xxh64, inputs::hash_file(f.toml));
  EXPECT_EQ(fabric.inputs[1].role, "height");
  EXPECT_EQ(fabric.inputs[1].path, dir / "height.exr") << "relative to the TOML's directory";
  EXPECT_EQ(fabric.inputs[1].xxh64, inputs::hash_file(dir / "height.exr"));
  EXPECT_EQ(fabric.inputs[2].role, "tangent");
  EXPECT_TRUE(take_warnings().empty());
}

TEST(FabricFiles, Xxh64OfKnownInputs) {
  EXPECT_EQ(inputs::xxh64_hex(""), "ef46db3751d8e999");  // XXH64 of no bytes, seed 0
  EXPECT_EQ(inputs::xxh64_hex("a").size(), 16u);
  EXPECT_NE(inputs::xxh64_hex("a"), inputs::xxh64_hex("b"));
}

TEST_F(FabricLoad, RelativePathsResolveAgainstTheTomlDirectoryNotTheWorkingDirectory) {
  ScratchDir dir;
  std::filesystem::create_directories(dir.path() / "sub");
  auto f = write_image_fabric(dir, 8);
  std::filesystem::rename(f.toml, dir / "sub/fabric.toml");
  // The maps are now one level up from the TOML: relative names must say so.
  std::string text = testing::read_text(dir / "sub/fabric.toml");
  text.replace(text.find("\"height.exr\""), 12, "\"../height.exr\"");
  text.replace(text.find("\"tangent.exr\""), 13, "\"../tangent.exr\"");
  write_text(dir / "sub/fabric.toml", text);
  EXPECT_NO_THROW(load_fabric(dir / "sub/fabric.toml"));
}

TEST_F(FabricLoad, PhysicalUnitsAreConvertedToTileSideUnits) {
  ScratchDir dir;
  // Tile 2 mm wide; heights stored in um, scaled by 0.5: h_tile = h * 0.5 * 0.001 / 2.
  auto f = write_image_fabric(dir, 8, "height_units = \"um\"\nheight_scale = 0.5\n",
                              "[tile]\nsize = 2.0\nunits = \"mm\"\n");
  Fabric fabric = load_fabric(f.toml);
  EXPECT_DOUBLE_EQ(fabric.tile_size_mm, 2.0);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      ASSERT_NEAR(fabric.maps.height[fabric.maps.index(x, y)],
                  float(testing::test_height(x, y, 8)) * 0.5 * 0.001 / 2.0, 1e-9);
  // Heights default to the tile's unit: stored in cm on a 0.5 cm tile -> divided by 0.5.
  ScratchDir dir2;
  auto g = write_image_fabric(dir2, 8, "", "[tile]\nsize = 0.5\nunits = \"cm\"\n");
  Fabric fabric2 = load_fabric(g.toml);
  EXPECT_DOUBLE_EQ(fabric2.tile_size_mm, 5.0);
  EXPECT_NEAR(fabric2.maps.height[3], float(testing::test_height(3, 0, 8)) / 0.5, 1e-7);
}

TEST_F(FabricLoad, UnitErrors) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[tile]\nunits = \"mm\"\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("tile.size is required when units = \"mm\""));
  f = write_image_fabric(dir, 8, "height_units = \"mm\"\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("maps.height_units = \"mm\" needs the tile's physical size"));
  f = write_image_fabric(dir, 8, "", "[tile]\nsize = 3\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("tile.size has no meaning with units = \"tile\""));
  f = write_image_fabric(dir, 8, "", "[tile]\nsize = 3\nunits = \"furlong\"\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("tile.units = \"furlong\" is not valid"));
}

TEST_F(FabricLoad, MissingTomlFile) {
  ScratchDir dir;
  std::string msg = load_error(dir / "nope.toml");
  EXPECT_THAT(msg, HasSubstr(dir / "nope.toml"));
  EXPECT_THAT(msg, HasSubstr("file not found"));
}

TEST_F(FabricLoad, TomlSyntaxErrorNamesLineAndColumn) {
  ScratchDir dir;
  write_text(dir / "bad.toml", "name = \"x\"\n[maps]\nheight = \"h.exr\n");
  std::string msg = load_error(dir / "bad.toml");
  EXPECT_THAT(msg, HasSubstr(dir / "bad.toml" + ":3:"));
  EXPECT_THAT(msg, HasSubstr("TOML syntax error"));
}

TEST_F(FabricLoad, UnknownKeyWithDidYouMean) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[[yarn]]\nname = \"a\"\nroughnes = 0.3\n");
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr(f.toml + ":8:"));
  EXPECT_THAT(msg, HasSubstr("unknown key 'yarn[0].roughnes'; did you mean 'yarn[0].roughness'?"));
  f = write_image_fabric(dir, 8, "", "[bkae]\nresolution = 8\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("unknown key 'bkae'; did you mean 'bake'?"));
  f = write_image_fabric(dir, 8, "normals = \"n.exr\"\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("did you mean 'maps.normal'?"));
}

TEST_F(FabricLoad, WrongTypeAndOutOfRange) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[bake]\nclusters = \"eight\"\n");
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr(f.toml + ":7:"));
  EXPECT_THAT(msg,
              HasSubstr("bake.clusters must be an integer in [1, 64], got a string (\"eight\")"));
  f = write_image_fabric(dir, 8, "", "[bake]\nclusters = 0\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("bake.clusters = 0 is out of range; valid range is [1, 64]"));
  f = write_image_fabric(dir, 8, "", "[[yarn]]\nroughness = 1.5\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("yarn[0].roughness = 1.5 is out of range; valid range is [0.0001, 1]"));
  f = write_image_fabric(dir, 8, "", "[sheen]\ncolor = [0.1, 0.2]\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("sheen.color must be a number or an array of 3 numbers"));
  f = write_image_fabric(dir, 8, "", "[bake]\ncompress = 1\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("bake.compress must be true or false"));
  f = write_image_fabric(dir, 8, "",
                         "[[yarn]]\ndiffuse_reflectance = 0.7\ndiffuse_transmittance = 0.5\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("exceeds 1 (energy is not conserved)"));
  f = write_image_fabric(dir, 8, "", "[bake]\ncompress_rank = 256\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("bake.compress_rank = 256 is out of range; valid range is [0, 255]"));
  f = write_image_fabric(dir, 8, "", "[bake]\nparallax_max_error = 0\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("bake.parallax_max_error = 0 is out of range; valid range is (0, 1]"));
  f = write_image_fabric(dir, 8, "", "[bake]\ncompress_clusters = -1\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("bake.compress_clusters = -1 is out of range; valid range is [0, 64]"));
  f = write_image_fabric(dir, 8, "", "[[yarn]]\nname = \"a\"\n[[yarn]]\nname = \"a\"\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("yarn[1].name = \"a\" is already the name of yarn[0]"));
}

TEST_F(FabricLoad, MissingRequiredMapKeyAndMissingFile) {
  ScratchDir dir;
  write_text(dir / "f.toml", "[maps]\nheight = \"h.exr\"\n");
  EXPECT_THAT(load_error(dir / "f.toml"), HasSubstr("maps.tangent is missing"));
  auto f = write_image_fabric(dir, 8, "gap = \"no-such-gap.png\"\n");
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr(f.toml + ":5:"));
  EXPECT_THAT(msg, HasSubstr("maps.gap"));
  EXPECT_THAT(msg, HasSubstr("no-such-gap.png: file not found"));
}

TEST_F(FabricLoad, UnreadableAndTruncatedImages) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "gap = \"gap.png\"\n");
  write_text(dir / "gap.png", "this is not a PNG file at all");
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr("maps.gap"));
  EXPECT_THAT(msg, HasSubstr("gap.png: cannot read"));

  // A real image cut in half.
  ScratchDir dir2;
  auto g = write_image_fabric(dir2, 64, "gap = \"gap.png\"\n");
  write_image(
      dir2 / "gap.png",
      make_image(64, 64, 1, [](int x, int y, int) { return ((x * 7 + y * 13) % 11) / 10.0; }),
      PixelType::UInt8);
  std::string bytes = testing::read_text(dir2 / "gap.png");
  write_text(dir2 / "gap.png", bytes.substr(0, bytes.size() / 2));
  msg = load_error(g.toml);
  EXPECT_THAT(msg, HasSubstr("maps.gap"));
  EXPECT_THAT(msg, HasSubstr("gap.png"));

  // An empty (zero-byte) file.
  write_text(dir2 / "gap.png", "");
  EXPECT_THAT(load_error(g.toml), HasSubstr("gap.png: cannot read"));
}

TEST_F(FabricLoad, WrongChannelCount) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  write_image(dir / "height.exr", make_image(8, 8, 3, [](int, int, int) { return 0.1; }),
              PixelType::Float32);
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr("maps.height"));
  EXPECT_THAT(msg, HasSubstr("image has 3 channels; a height map needs 1 channel"));
}

TEST_F(FabricLoad, MapsOfDifferentSizes) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "gap = \"gap.exr\"\n");
  write_image(dir / "gap.exr", make_image(16, 16, 1, [](int, int, int) { return 1.0; }),
              PixelType::Float32);
  EXPECT_THAT(load_error(f.toml), HasSubstr("image is 16x16 but maps.height is 8x8"));
}

TEST_F(FabricLoad, NonSquareAndTooSmallMaps) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  write_image(dir / "height.exr", make_image(8, 4, 1, [](int, int, int) { return 0.1; }),
              PixelType::Float32);
  EXPECT_THAT(load_error(f.toml), HasSubstr("image is 8x4; feature maps must be square"));
  ScratchDir dir2;
  auto g = write_image_fabric(dir2, 2);
  EXPECT_THAT(load_error(g.toml), HasSubstr("image is 2x2; map resolution must be in [4, 8192]"));
}

TEST_F(FabricLoad, OversizedImageIsRejectedFromItsHeader) {
  // 8193 x 1 pixels: tiny on disk; the side limit is checked before the pixels are read.
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "gap = \"wide.png\"\n");
  write_image(dir / "wide.png", make_image(8193, 1, 1, [](int, int, int) { return 1.0; }),
              PixelType::UInt8);
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("image is 8193x1; map resolution must be at most 8192"));
}

TEST_F(FabricLoad, NanAndInfPixelsAreNamed) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  write_image(
      dir / "height.exr",
      make_image(8, 8, 1,
                 [](int x, int y, int) { return x == 5 && y == 2 ? std::nan("") : 0.1 * x; }),
      PixelType::Float32);
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr("maps.height"));
  EXPECT_THAT(msg, HasSubstr("height.exr"));
  EXPECT_THAT(msg, HasSubstr("pixel (5, 2) channel 0 is NaN"));

  f = write_image_fabric(dir, 8);
  write_image(
      dir / "tangent.exr",
      make_image(8, 8, 3,
                 [](int x, int y, int c) { return x == 0 && y == 7 && c == 1 ? INFINITY : 0.5; }),
      PixelType::Float32);
  msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr("maps.tangent"));
  EXPECT_THAT(msg, HasSubstr("pixel (0, 7) channel 1 is infinite"));
}

TEST_F(FabricLoad, ZeroLengthTangentIsNamed) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  write_image(
      dir / "tangent.exr",
      make_image(8, 8, 3,
                 [](int x, int y, int c) { return x == 6 && y == 3 ? 0.0 : (c == 0 ? 1.0 : 0.0); }),
      PixelType::Float32);
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr("maps.tangent"));
  EXPECT_THAT(msg, HasSubstr("pixel (6, 3) has a zero-length tangent"));
  // The 8-bit encoding of the zero vector (mid-grey) is zero-length too.
  ScratchDir dir2;
  auto g = write_image_fabric(dir2, 8, "", "");
  write_image(dir2 / "tangent.png",
              make_image(8, 8, 3,
                         [](int x, int y, int c) {
                           return x == 1 && y == 1 ? 128 / 255.0 : (c == 0 ? 1.0 : 0.5);
                         }),
              PixelType::UInt8);
  std::string text = testing::read_text(g.toml);
  text.replace(text.find("tangent.exr"), 11, "tangent.png");
  write_text(g.toml, text);
  EXPECT_THAT(load_error(g.toml), HasSubstr("pixel (1, 1) has a zero-length tangent"));
}

TEST_F(FabricLoad, ConstantHeightIsAllowedWithAWarning) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8);
  write_image(dir / "height.exr", make_image(8, 8, 1, [](int, int, int) { return 0.25; }),
              PixelType::Float32);
  Fabric fabric = load_fabric(f.toml);
  for (const auto& n : fabric.maps.normal)
    EXPECT_EQ(n, (Vec3f{0, 0, 1}));
  auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("maps.height"));
  EXPECT_THAT(warnings[0], HasSubstr("the height map is constant (h = 0.25)"));
}

TEST_F(FabricLoad, YarnIdsMustIndexDeclaredYarns) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "yarn_id = \"ids.png\"\n",
                              "[[yarn]]\nname = \"a\"\n[[yarn]]\nname = \"b\"\n");
  write_image(
      dir / "ids.png",
      make_image(8, 8, 1, [](int x, int y, int) { return (x == 4 && y == 6 ? 2 : x % 2) / 255.0; }),
      PixelType::UInt8);
  std::string msg = load_error(f.toml);
  EXPECT_THAT(msg, HasSubstr("maps.yarn_id"));
  EXPECT_THAT(msg,
              HasSubstr("pixel (4, 6) has yarn id 2 but only 2 yarns are declared (ids 0..1)"));
  // Fixed map: ids 0/1 index the two yarns; albedo defaults to each texel's yarn colour.
  write_image(dir / "ids.png", make_image(8, 8, 1, [](int x, int, int) { return (x % 2) / 255.0; }),
              PixelType::UInt8);
  write_text(f.toml, testing::read_text(f.toml) + "");
  std::string text = testing::read_text(f.toml);
  text.replace(text.find("name = \"b\""), 10, "name = \"b\"\ncolor = [0.5, 0.25, 0]");
  write_text(f.toml, text);
  Fabric fabric = load_fabric(f.toml);
  EXPECT_EQ(fabric.maps.yarn_id[fabric.maps.index(3, 0)], 1);
  EXPECT_EQ(fabric.maps.albedo[fabric.maps.index(3, 0)], (Vec3f{0.5f, 0.25f, 0.f}));
  EXPECT_EQ(fabric.maps.albedo[fabric.maps.index(2, 0)], (Vec3f{1, 1, 1}));
}

TEST_F(FabricLoad, UnusedYarnWarns) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[[yarn]]\nname = \"a\"\n[[yarn]]\nname = \"spare\"\n");
  load_fabric(f.toml);
  auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("yarn[1] 'spare' is declared but no texel uses it"));
}

TEST_F(FabricLoad, AlbedosAboveOneWarnNamingTheYarnAndTheDefaultsDoNot) {
  ScratchDir dir;
  auto f =
      write_image_fabric(dir, 8, "", "[[yarn]]\nname = \"a\"\nspecular_albedo = [0.6, 0.9, 0.6]\n");
  load_fabric(f.toml);
  auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("yarn[0].specular_albedo [1]"));
  EXPECT_THAT(warnings[0], HasSubstr("= 1.3 exceeds 1"));
  // The defaults (0.6 + 0.25 + 0.15) sum to exactly 1: no warning.
  auto g = write_image_fabric(dir, 8, "", "[[yarn]]\nname = \"a\"\n");
  load_fabric(g.toml);
  EXPECT_TRUE(take_warnings().empty());
}

TEST_F(FabricLoad, BakeResolutionMustMatchTheMaps) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[bake]\nresolution = 16\n");
  EXPECT_THAT(load_error(f.toml),
              HasSubstr("bake.resolution = 16 but the maps are 8x8; maps are not resampled"));
  f = write_image_fabric(dir, 8, "", "[bake]\nresolution = 8\n");
  EXPECT_EQ(load_fabric(f.toml).bake.resolution, 8);
  LoadOptions options;
  options.resolution = 32;
  EXPECT_THAT(error_message([&] { load_fabric_description(f.toml, options); }),
              HasSubstr("resolution = 32 but the maps are 8x8"));
}

TEST_F(FabricLoad, MapsAndWeaveAreExclusive) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[weave]\nname = \"plain\"\n");
  EXPECT_THAT(load_error(f.toml), HasSubstr("[maps] and [weave] cannot both be given"));
  write_text(dir / "empty.toml", "name = \"x\"\n");
  EXPECT_THAT(load_error(dir / "empty.toml"), HasSubstr("no [maps] or [weave] section"));
}

TEST_F(FabricLoad, NamedWeave) {
  ScratchDir dir;
  write_text(dir / "w.toml",
             "[weave]\nname = \"twill2/1\"\n[weave.warp]\nspacing_mm = "
             "0.4\n[weave.weft]\nspacing_mm = 0.4\n"
             "[[yarn]]\ncolor = [0.1, 0.2, 0.3]\n[[yarn]]\ncolor = [0.9, 0.8, "
             "0.7]\n[bake]\nresolution = 24\n");
  LoadedFabric loaded = load_fabric_description(dir / "w.toml");
  const Fabric& f = loaded.fabric;
  EXPECT_EQ(loaded.source, FabricSource::NamedWeave);
  EXPECT_EQ(loaded.weave_label, "twill2/1");
  ASSERT_TRUE(loaded.weave.has_value());
  EXPECT_EQ(loaded.weave->matrix, weave::named_weave("twill2/1"));
  EXPECT_EQ(f.maps.resolution, 24);
  EXPECT_NEAR(f.tile_size_mm, 3 * 0.4, 1e-12) << "one repeat of 3 ends at 0.4 mm";
  ASSERT_EQ(f.yarns.size(), 2u);
  EXPECT_EQ(f.yarns[0].name, "warp");
  EXPECT_EQ(f.yarns[1].name, "weft");
  // Threads without their own colour take their yarn's colour: warp texels are (0.1, 0.2, 0.3).
  bool saw_warp = false, saw_weft = false;
  for (std::size_t i = 0; i < f.maps.texel_count(); ++i) {
    if (f.maps.gap[i] < 0.5f) continue;
    if (f.maps.yarn_id[i] == 0) {
      saw_warp = true;
      EXPECT_EQ(f.maps.albedo[i], (Vec3f{0.1f, 0.2f, 0.3f}));
    } else {
      saw_weft = true;
      EXPECT_EQ(f.maps.albedo[i], (Vec3f{0.9f, 0.8f, 0.7f}));
    }
  }
  EXPECT_TRUE(saw_warp && saw_weft);
  // Same maps as the generator called directly.
  weave::WeaveSpec spec = *loaded.weave;
  FabricMaps direct = weave::generate_weave_maps(spec, 24);
  EXPECT_EQ(direct.height, f.maps.height);
  EXPECT_EQ(direct.yarn_id, f.maps.yarn_id);
}

TEST_F(FabricLoad, MatrixWeaveWithThreadColours) {
  ScratchDir dir;
  write_text(
      dir / "m.toml",
      "[weave]\nmatrix = [\"1100\", \"0110\", \"0011\", \"1001\"]\n"
      "end_colors = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]]\n[bake]\nresolution = 16\n");
  LoadedFabric loaded = load_fabric_description(dir / "m.toml");
  EXPECT_EQ(loaded.source, FabricSource::MatrixWeave);
  EXPECT_EQ(loaded.weave->matrix.to_rows(),
            (std::vector<std::string>{"1100", "0110", "0011", "1001"}));
  EXPECT_EQ(loaded.weave->end_colors.size(), 4u);
  EXPECT_EQ(loaded.weave->pick_colors, std::vector<Rgb>(4, Rgb{1, 1, 1}));
}

// A repeat far from square warns with the repeat counts that come nearest square; [weave] repeat
// applies them (no warning then), and a bad value names the key.
TEST_F(FabricLoad, NonSquareRepeatWarnsAndRepeatTilesIt) {
  ScratchDir dir;
  const std::string wif = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/wif/twill-2-2.wif";
  write_text(dir / "w.toml", "[weave]\nwif = \"" + wif + "\"\n[bake]\nresolution = 16\n");
  take_warnings();
  const LoadedFabric one = load_fabric_description(dir / "w.toml");
  auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr("H/W 0.5"));
  EXPECT_THAT(warnings[0], HasSubstr("repeat = [1, 2]"));
  write_text(dir / "w.toml",
             "[weave]\nwif = \"" + wif + "\"\nrepeat = [1, 2]\n[bake]\nresolution = 16\n");
  const LoadedFabric two = load_fabric_description(dir / "w.toml");
  EXPECT_TRUE(take_warnings().empty());
  EXPECT_EQ(two.weave->matrix.picks, 2 * one.weave->matrix.picks);
  EXPECT_EQ(two.fabric.tile_size_mm, one.fabric.tile_size_mm);
  for (const char* bad : {"repeat = [1.5, 2]", "repeat = [0, 1]", "repeat = [1]", "repeat = 2"}) {
    write_text(dir / "w.toml", "[weave]\nwif = \"" + wif + "\"\n" + bad + "\n");
    EXPECT_THAT(load_error(dir / "w.toml"), HasSubstr("weave.repeat")) << bad;
  }
}

TEST_F(FabricLoad, WifWeaveWithGeometryOverrides) {
  ScratchDir dir;
  std::string wif = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/wif/twill-2-2.wif";
  write_text(dir / "w.toml", "[weave]\nwif = \"" + wif +
                                 "\"\n[weave.warp]\ntwist_deg = -15\n[bake]\nresolution = 16\n");
  LoadedFabric loaded = load_fabric_description(dir / "w.toml");
  EXPECT_EQ(loaded.source, FabricSource::Wif);
  ASSERT_TRUE(loaded.weave);
  EXPECT_EQ(loaded.weave->warp.twist_deg, -15.0);
  for (const auto& g : loaded.weave->end_geometry)
    EXPECT_EQ(g.twist_deg, -15.0);
  WifDraft draft = read_wif(wif);
  EXPECT_EQ(loaded.weave->matrix, draft.spec.matrix);
  EXPECT_EQ(loaded.weave->weft.twist_deg, draft.spec.weft.twist_deg) << "only stated keys override";
  // The draft's spacings stay where the file states none ([weave.weft] absent: they were replaced
  // by the defaults, a 4 x 2 mm tile instead of the draft's 10.16 x 5.08 mm).
  EXPECT_EQ(loaded.weave->weft.spacing_mm, draft.spec.weft.spacing_mm);
  EXPECT_EQ(loaded.weave->warp.spacing_mm, draft.spec.warp.spacing_mm);
  EXPECT_EQ(loaded.fabric.tile_size_mm, weave::weave_tile_size(draft.spec).width_mm);
  ASSERT_EQ(loaded.fabric.inputs.size(), 2u);
  EXPECT_EQ(loaded.fabric.inputs[1].role, "wif");
  EXPECT_EQ(loaded.fabric.inputs[1].xxh64, inputs::hash_file(wif));
  // pattern --wif builds the same maps with the draft's own geometry.
  LoadedFabric direct = fabric_from_wif(wif, 16);
  EXPECT_EQ(direct.weave->matrix, draft.spec.matrix);
  EXPECT_EQ(direct.fabric.maps.resolution, 16);
}

TEST_F(FabricLoad, WeaveErrors) {
  ScratchDir dir;
  auto expect = [&](const std::string& text, const std::string& fragment) {
    write_text(dir / "w.toml", text);
    EXPECT_THAT(load_error(dir / "w.toml"), HasSubstr(fragment)) << text;
  };
  expect("[weave]\nname = \"twil2/1\"\n", "weave.name");
  expect("[weave]\nname = \"plain\"\nmatrix = [\"01\", \"10\"]\n", "needs exactly one of");
  expect("[weave]\n", "none is given");
  expect("[weave]\nmatrix = [\"0120\", \"1001\"]\n", "weave.matrix");
  expect("[weave]\nmatrix = [\"11\", \"11\"]\n", "weave.matrix");  // nothing interlaces
  expect("[weave]\nname = \"plain\"\n[weave.warp]\nwidth = 1.5\n",
         "weave.warp.width = 1.5 is out of range; valid range is (0, 1]");
  expect("[weave]\nname = \"plain\"\n[weave.warp]\nspacing = 0.3\n",
         "did you mean 'weave.warp.spacing_mm'?");
  expect("[weave]\nname = \"plain\"\nend_colors = [[1, 0, 0]]\n",
         "end_colors has 1 colours but the weave has 2 ends");
  expect("[weave]\nname = \"plain\"\n[[yarn]]\nname = \"only\"\n", "only 1 [[yarn]] is declared");
  expect("[weave]\nname = \"plain\"\n[tile]\nsize = 2\nunits = \"mm\"\n",
         "cannot be combined with [weave]");
  expect("[weave]\nwif = \"missing.wif\"\n", "missing.wif");
}

TEST_F(FabricLoad, ExampleFabricsLoad) {
  // Every bundled example is valid (at a small resolution to keep the test fast).
  for (const char* name : {"plain", "twill", "satin", "diamond", "argyle"}) {
    std::string path = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/" + name + ".toml";
    LoadOptions options;
    options.resolution = 32;
    LoadedFabric loaded;
    ASSERT_NO_THROW(loaded = load_fabric_description(path, options)) << path;
    EXPECT_EQ(loaded.fabric.maps.resolution, 32);
    EXPECT_EQ(loaded.fabric.yarns.size(), 2u);
    EXPECT_GT(loaded.fabric.tile_size_mm, 0.0);
  }
  EXPECT_TRUE(take_warnings().empty());
}

TEST_F(FabricLoad, TwillExampleKeepsThePaperResolution) {
  // The demo relies on the twill example baking at 256 x 256 (the paper's resolution).
  std::string text =
      testing::read_text(std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/twill.toml");
  EXPECT_THAT(text, HasSubstr("resolution = 256"));
}

TEST_F(FabricLoad, CompressShapeKeysZeroMeansAuto) {
  ScratchDir dir;
  auto f = write_image_fabric(dir, 8, "", "[bake]\ncompress_clusters = 0\ncompress_rank = 0\n");
  Fabric fabric = load_fabric_description(f.toml).fabric;
  EXPECT_EQ(fabric.bake.compress_clusters, 0);
  EXPECT_EQ(fabric.bake.compress_rank, 0);
  f = write_image_fabric(dir, 8, "", "[bake]\ncompress_clusters = 3\ncompress_rank = 12\n");
  fabric = load_fabric_description(f.toml).fabric;
  EXPECT_EQ(fabric.bake.compress_clusters, 3);
  EXPECT_EQ(fabric.bake.compress_rank, 12);
}

TEST(FabricDefaults, YarnAlbedosConserveEnergy) {
  // alpha + R_d + T_d <= 1 per channel (model::energy_excess <= 0): a fabric that leaves the
  // albedos out must not reflect and transmit more than it receives.
  const YarnMaterial y;
  for (int c = 0; c < 3; ++c) {
    EXPECT_LE(y.specular_albedo[c] + y.diffuse_reflectance[c] + y.diffuse_transmittance[c], 1.0)
        << "channel " << c;
    EXPECT_GT(y.specular_albedo[c], y.diffuse_reflectance[c]) << "specular stays the main lobe";
    EXPECT_GT(y.diffuse_reflectance[c], y.diffuse_transmittance[c]);
  }
}

}  // namespace
}  // namespace clothbake

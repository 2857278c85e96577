// bake/inputs/scene_load.hpp: a scene's physical units (top-level `units`, an object's `tile_mm` or
// its fabric's own tile side) and the [render] preview keys (exposure, tone_map, background).
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/scene_load.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/layout.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/bake/inputs/test_support.hpp"

namespace {

using namespace clothbake;
using clothbake::testing::error_message;
using clothbake::testing::ScratchDir;
using clothbake::testing::write_text;

// A plain weave (2 x 2) at 0.25 mm spacing, so a tile 0.5 mm wide; at 16 texels it loads in
// milliseconds.
const char* kWovenFabric =
    "[weave]\nname = \"plain\"\n[weave.warp]\nspacing_mm = 0.25\n[weave.weft]\nspacing_mm = "
    "0.25\n[bake]\nresolution = 16\n";

std::string scene_with(const std::string& top, const std::string& object_keys,
                       const std::string& render = "") {
  return top + "\n[camera]\nposition = [0, 0, 3]\n" + render +
         "\n[[light]]\ntype = \"point\"\nposition = [0, 1, 2]\n\n[[object]]\nshape = "
         "\"plane\"\n" +
         object_keys;
}

inputs::LoadedScene load(const ScratchDir& dir, const std::string& text) {
  write_text(dir / "scene.toml", text);
  return inputs::load_scene(dir / "scene.toml");
}

TEST(SceneUnits, TheFabricsOwnTileSideSetsTheTilesPerUnit) {
  ScratchDir dir;
  write_text(dir / "plain.toml", kWovenFabric);
  const double tile_mm = clothbake::load_fabric_description(dir / "plain.toml").fabric.tile_size_mm;
  ASSERT_NEAR(tile_mm, 0.5, 1e-12);  // two ends at 0.25 mm
  // 1 m over the tile's side; the same scene in centimetres has a hundredth as many.
  const auto metres = load(dir, scene_with("units = \"m\"", "fabric = \"plain.toml\"\n"));
  EXPECT_NEAR(metres.scene.objects[0].tiles_per_unit, 1000.0 / tile_mm, 1e-9);
  const auto cm = load(dir, scene_with("units = \"cm\"", "fabric = \"plain.toml\"\n"));
  EXPECT_NEAR(cm.scene.objects[0].tiles_per_unit, 10.0 / tile_mm, 1e-12);
  const auto inches = load(dir, scene_with("units = \"in\"", "fabric = \"plain.toml\"\n"));
  EXPECT_NEAR(inches.scene.objects[0].tiles_per_unit, 25.4 / tile_mm, 1e-12);
  // tile_mm overrides the fabric's side; tiles_per_unit is taken as given whatever the units.
  const auto given =
      load(dir, scene_with("units = \"m\"", "fabric = \"plain.toml\"\ntile_mm = 2\n"));
  EXPECT_DOUBLE_EQ(given.scene.objects[0].tiles_per_unit, 500.0);
  const auto explicit_count =
      load(dir, scene_with("units = \"m\"", "fabric = \"plain.toml\"\ntiles_per_unit = 7\n"));
  EXPECT_DOUBLE_EQ(explicit_count.scene.objects[0].tiles_per_unit, 7.0);
  // Without units nothing changes: 1 tile per unit, or what the object says.
  const auto plain = load(dir, scene_with("", "fabric = \"plain.toml\"\n"));
  EXPECT_DOUBLE_EQ(plain.scene.objects[0].tiles_per_unit, 1.0);
  // A diffuse object ignores the units.
  const auto diffuse = load(dir, scene_with("units = \"m\"", "color = 0.5\n"));
  EXPECT_DOUBLE_EQ(diffuse.scene.objects[0].tiles_per_unit, 1.0);
}

TEST(SceneUnits, AnAssetsTileSideIsReadOnlyWhenItsChecksumsHold) {
  ScratchDir dir;
  write_text(dir / "plain.toml", kWovenFabric);
  const Fabric fabric = clothbake::load_fabric_description(dir / "plain.toml").fabric;
  std::vector<formats::Section> sections = fabric_record_sections(fabric);
  sections.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  const std::vector<std::byte> bytes = formats::serialize_asset(sections);
  auto write_asset = [&](const std::vector<std::byte>& b) {
    write_text(dir / "a.cbk", std::string(reinterpret_cast<const char*>(b.data()), b.size()));
  };
  write_asset(bytes);
  const auto metres = load(dir, scene_with("units = \"m\"", "asset = \"a.cbk\"\n"));
  EXPECT_NEAR(metres.scene.objects[0].tiles_per_unit, 1000.0 / fabric.tile_size_mm, 1e-9);
  // The tile side's top byte changed (a side 65 536 times smaller), checksums not recomputed: the
  // scene refuses the asset instead of scaling the cloth by it.
  std::vector<std::byte> damaged = bytes;
  std::vector<uint64_t> words((bytes.size() + 7) / 8);
  std::memcpy(words.data(), bytes.data(), bytes.size());
  reader::Asset asset;
  ASSERT_TRUE(asset.open_memory(words.data(), bytes.size()).ok());
  reader::SectionInfo info;
  ASSERT_TRUE(asset.find(reader::SectionType::FabricInfo, 0, &info).ok());
  damaged[info.offset + offsetof(reader::FabricInfoRecord, tile_size_mm) + 7] ^= std::byte{0x01};
  write_asset(damaged);
  write_text(dir / "scene.toml", scene_with("units = \"m\"", "asset = \"a.cbk\"\n"));
  const std::string message = error_message([&] { inputs::load_scene(dir / "scene.toml"); });
  EXPECT_NE(message.find("object[0].asset"), std::string::npos) << message;
  EXPECT_NE(message.find("tile size"), std::string::npos) << message;
}

TEST(SceneUnits, MissingOrContradictoryScalesNameTheKey) {
  ScratchDir dir;
  write_text(dir / "plain.toml", kWovenFabric);
  // An image fabric in tile units (no [tile] size) has no physical side.
  const clothbake::testing::ImageFabric tile_units = clothbake::testing::write_image_fabric(dir);
  auto message = [&](const std::string& text) {
    write_text(dir / "bad.toml", text);
    return error_message([&] { inputs::load_scene(dir / "bad.toml"); });
  };
  const std::string no_units = message(scene_with("", "fabric = \"plain.toml\"\ntile_mm = 1\n"));
  EXPECT_NE(no_units.find("object[0].tile_mm"), std::string::npos) << no_units;
  EXPECT_NE(no_units.find("units = \"m\""), std::string::npos) << no_units;
  const std::string both = message(
      scene_with("units = \"m\"", "fabric = \"plain.toml\"\ntile_mm = 1\ntiles_per_unit = 2\n"));
  EXPECT_NE(both.find("exclusive"), std::string::npos) << both;
  const std::string bad_unit = message(scene_with("units = \"mn\"", "color = 0.5\n"));
  EXPECT_NE(bad_unit.find("units"), std::string::npos) << bad_unit;
  EXPECT_NE(bad_unit.find("\"mm\""), std::string::npos) << bad_unit;  // did you mean
  const std::string zero = message(scene_with("units = \"m\"", "tile_mm = 0\ncolor = 0.5\n"));
  EXPECT_NE(zero.find("object[0].tile_mm"), std::string::npos) << zero;
  // A tile so small that the count leaves tiles_per_unit's range (1e15 per metre).
  const std::string tiny =
      message(scene_with("units = \"m\"", "fabric = \"plain.toml\"\ntile_mm = 1e-12\n"));
  EXPECT_NE(tiny.find("object[0].tile_mm"), std::string::npos) << tiny;
  EXPECT_NE(tiny.find("tiles per world unit"), std::string::npos) << tiny;
  // The fabric in tile units: the message says what to give instead.
  const std::string unknown_side =
      message(scene_with("units = \"m\"", "fabric = \"" + tile_units.toml + "\"\n"));
  EXPECT_NE(unknown_side.find("object[0].fabric"), std::string::npos) << unknown_side;
  EXPECT_NE(unknown_side.find("no physical tile size"), std::string::npos) << unknown_side;
  EXPECT_NE(unknown_side.find("tile_mm or tiles_per_unit"), std::string::npos) << unknown_side;
}

TEST(SceneRender, PreviewKeysAndTheBackdrop) {
  ScratchDir dir;
  const auto defaults = load(dir, scene_with("", "color = 0.5\n"));
  EXPECT_EQ(defaults.scene.preview.exposure, 0.0);
  EXPECT_EQ(defaults.scene.preview.tone_map, render::ToneMap::Clamp);
  EXPECT_EQ(defaults.scene.background.g, 0.0);
  const auto set = load(dir, scene_with("", "color = 0.5\n",
                                        "[render]\nexposure = -1.5\ntone_map = \"filmic\"\n"
                                        "background = [0.1, 0.2, 0.3]\n"));
  EXPECT_EQ(set.scene.preview.exposure, -1.5);
  EXPECT_EQ(set.scene.preview.tone_map, render::ToneMap::Filmic);
  EXPECT_EQ(set.scene.background.b, 0.3);
  auto message = [&](const std::string& render) {
    write_text(dir / "bad.toml", scene_with("", "color = 0.5\n", render));
    return error_message([&] { inputs::load_scene(dir / "bad.toml"); });
  };
  EXPECT_NE(message("[render]\nexposure = 40\n").find("render.exposure"), std::string::npos);
  EXPECT_NE(message("[render]\ntone_map = \"aces\"\n").find("render.tone_map"), std::string::npos);
  EXPECT_NE(message("[render]\nbackground = -1\n").find("render.background"), std::string::npos);
  // An environment light is the background already.
  write_text(dir / "env.toml",
             "[camera]\n[render]\nbackground = 0.1\n[[light]]\ntype = \"environment\"\nmap = "
             "\"" +
                 std::string(CLOTHBAKE_SOURCE_DIR) +
                 "/examples/scenes/sky.exr\"\n[[object]]\nshape = \"plane\"\n");
  const std::string env = error_message([&] { inputs::load_scene(dir / "env.toml"); });
  EXPECT_NE(env.find("render.background"), std::string::npos) << env;
  EXPECT_NE(env.find("light[0]"), std::string::npos) << env;
}

}  // namespace

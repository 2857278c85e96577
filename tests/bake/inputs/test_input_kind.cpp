// bake/inputs/input_kind.hpp and the loaders that use it: a WIF draft given as a fabric is read as
// one; a scene, an asset or a fabric given where the other is needed is named as what it is.
#include <gtest/gtest.h>

#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/input_kind.hpp"
#include "bake/inputs/scene_load.hpp"
#include "tests/bake/inputs/test_support.hpp"
#include "tests/support/input_error.hpp"

namespace {

using namespace clothbake;
using clothbake::inputs::InputKind;
using clothbake::inputs::sniff_input_kind;

const std::string kExamples = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/";

TEST(InputKind, HeadersAtTheStartOfALineDecide) {
  EXPECT_EQ(sniff_input_kind("name = \"x\"\n[weave]\nname = \"plain\"\n"), InputKind::Fabric);
  EXPECT_EQ(sniff_input_kind("  [weave.warp] # geometry\nspacing_mm = 1\n"), InputKind::Fabric);
  EXPECT_EQ(sniff_input_kind("[[yarn]]\r\nname = \"a\"\r\n"), InputKind::Fabric);
  EXPECT_EQ(sniff_input_kind("[camera]\nfov_deg = 30\n[[object]]\n"), InputKind::Scene);
  EXPECT_EQ(sniff_input_kind("; a draft\n[wif]\nVersion=1.1\n[WEAVING]\n"), InputKind::Wif);
  EXPECT_EQ(sniff_input_kind(std::string("\x89"
                                         "CBK\r\n\x1a\n",
                                         8) +
                             std::string(100, '\0')),
            InputKind::Asset);
  // Neither, both, a longer name, a header inside a string value: Unknown.
  EXPECT_EQ(sniff_input_kind(""), InputKind::Unknown);
  EXPECT_EQ(sniff_input_kind("[bakery]\n[cameras]\n"), InputKind::Unknown);
  EXPECT_EQ(sniff_input_kind("[camera]\n[bake]\n"), InputKind::Unknown);
  EXPECT_EQ(sniff_input_kind("name = \"[camera]\"\n"), InputKind::Unknown);
  EXPECT_EQ(sniff_input_kind(std::string(1000, '\xff')), InputKind::Unknown);
}

// A WIF draft is a fabric, by its name or by its content, at the given resolution or 256.
TEST(InputKind, AWifDraftLoadsAsAFabric) {
  const std::string wif = kExamples + "wif/twill-2-2.wif";
  const LoadedFabric a = load_fabric_description(wif);
  EXPECT_EQ(a.source, FabricSource::Wif);
  EXPECT_EQ(a.fabric.maps.resolution, kDefaultWeaveResolution);
  EXPECT_GT(a.fabric.bake.radiance_dirs, 0);  // resolved, as for a [weave] without [bake]
  LoadOptions small;
  small.resolution = 32;
  const LoadedFabric b = load_fabric_description(wif, small);
  EXPECT_EQ(b.fabric.maps.resolution, 32);
  // The same draft under another name: recognised by its [WIF] section.
  clothbake::testing::ScratchDir dir;
  clothbake::testing::write_text(dir / "draft.txt", clothbake::testing::read_text(wif));
  const LoadedFabric c = load_fabric_description(dir / "draft.txt", small);
  EXPECT_EQ(c.source, FabricSource::Wif);
  EXPECT_EQ(c.fabric.maps.height, b.fabric.maps.height);
  const auto peek = peek_fabric_settings(wif, small);
  ASSERT_TRUE(peek.has_value());
  EXPECT_EQ(peek->bake.resolution, 32);
}

TEST(InputKind, TheWrongKindIsNamedBeforeAnyTomlError) {
  const std::string scene = kExamples + "scenes/room.toml",
                    fabric = kExamples + "fabrics/twill.toml";
  std::string m = test_support::input_error_of([&] { (void)load_fabric_description(scene); });
  EXPECT_NE(m.find(scene + " is a scene, not a fabric description"), std::string::npos) << m;
  m = test_support::input_error_of([&] { (void)inputs::load_scene(fabric); });
  EXPECT_NE(m.find(fabric + " is a fabric description, not a scene"), std::string::npos) << m;
  clothbake::testing::ScratchDir dir;
  clothbake::testing::write_text(dir / "a.cbk", std::string("\x89"
                                                            "CBK\r\n\x1a\n",
                                                            8) +
                                                    "rest");
  m = test_support::input_error_of([&] { (void)load_fabric_description(dir / "a.cbk"); });
  EXPECT_NE(m.find("is a clothbake asset, not a fabric description"), std::string::npos) << m;
  m = test_support::input_error_of(
      [&] { (void)inputs::load_scene(kExamples + "wif/twill-2-2.wif"); });
  EXPECT_NE(m.find("is a WIF draft, not a scene"), std::string::npos) << m;
}

}  // namespace

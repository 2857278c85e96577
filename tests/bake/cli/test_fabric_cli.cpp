// `clothbake inspect` and `clothbake pattern` run as processes through the built binary: exit
// codes, JSON schema on stdout, diagnostics on stderr, nothing written on failure, round trip.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "tests/bake/inputs/test_support.hpp"
#include "tests/support/run_cli.hpp"

namespace clothbake {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::read_text;
using testing::ScratchDir;
using testing::write_text;

const std::string kExamples = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/";

struct ProcessResult {
  int exit_code = -1;
  std::string out, err;
};

// `clothbake ARGS...`, each element one argument (no shell). `dir` is unused: kept so that every
// call names the scratch directory the command works in.
ProcessResult run_cli(const ScratchDir& /*dir*/, const std::vector<std::string>& args) {
  const test_support::CliRun r = test_support::run_clothbake(args);
  return {r.code, r.out, r.err};
}

void expect_stats(const nlohmann::json& s) {
  for (const char* key : {"min", "max", "mean", "stddev"})
    EXPECT_TRUE(s.at(key).is_number()) << key;
  EXPECT_LE(s["min"].get<double>(), s["mean"].get<double>());
  EXPECT_LE(s["mean"].get<double>(), s["max"].get<double>());
}

TEST(CliInspect, JsonSchemaOfAWeaveFabric) {
  ScratchDir dir;
  // A small copy of the twill example so that the test stays fast.
  std::string text = read_text(kExamples + "twill.toml");
  text.replace(text.find("resolution = 256"), 16, "resolution = 32");
  write_text(dir / "twill.toml", text);
  ProcessResult r = run_cli(dir, {"inspect", dir / "twill.toml", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["name"], "cotton twill 3/1");
  EXPECT_EQ(doc["source"], "named_weave");
  EXPECT_EQ(doc["resolution"], 32);
  EXPECT_EQ(doc["fabric"], dir / "twill.toml");
  EXPECT_EQ(doc["weave"]["picks"], 4);
  EXPECT_EQ(doc["weave"]["ends"], 4);
  EXPECT_EQ(doc["weave"]["matrix"].size(), 4u);
  EXPECT_EQ(doc["weave"]["matrix"][0], "1110");  // twill 3/1: warp up on ends 0..2 of pick 0
  for (const char* map : {"height", "tangent", "normal", "gap", "yarn_id", "albedo"}) {
    ASSERT_TRUE(doc["maps"].contains(map)) << map;
    EXPECT_EQ(doc["maps"][map]["origin"], "weave");
    EXPECT_TRUE(doc["maps"][map]["file"].is_null());
  }
  expect_stats(doc["maps"]["height"]);
  expect_stats(doc["maps"]["gap"]);
  for (const char* c : {"x", "y", "z"})
    expect_stats(doc["maps"]["tangent"][c]);
  for (const char* c : {"r", "g", "b"})
    expect_stats(doc["maps"]["albedo"][c]);
  double gap_fraction = doc["maps"]["gap"]["gap_fraction"];
  EXPECT_GE(gap_fraction, 0.0);
  EXPECT_LT(gap_fraction, 0.5);
  double along_x = doc["maps"]["tangent"]["fraction_along_x"],
         along_y = doc["maps"]["tangent"]["fraction_along_y"];
  EXPECT_GT(along_y, along_x) << "a 3/1 twill shows mostly warp (along y) on its face";
  EXPECT_EQ(doc["maps"]["yarn_id"]["texels_per_yarn"].size(), 2u);
  EXPECT_EQ(doc["yarns"].size(), 2u);
  EXPECT_EQ(doc["yarns"][0]["name"], "warp");
  EXPECT_DOUBLE_EQ(doc["yarns"][0]["roughness"].get<double>(), 0.40);
  EXPECT_EQ(doc["bake"]["clusters"], 8) << "defaults are filled in";
  EXPECT_EQ(doc["bake"]["compress_rank"], 0) << "0: ranks chosen for the target error";
  EXPECT_DOUBLE_EQ(doc["sheen"]["roughness"].get<double>(), 0.45);
  EXPECT_TRUE(doc["tile"]["size_mm"].is_number());
  ASSERT_EQ(doc["inputs"].size(), 1u);
  EXPECT_EQ(doc["inputs"][0]["role"], "fabric");
  EXPECT_EQ(doc["inputs"][0]["xxh64"].get<std::string>().size(), 16u);
  EXPECT_TRUE(doc["warnings"].is_array());
}

TEST(CliInspect, HumanReadableByDefault) {
  ScratchDir dir;
  auto f = testing::write_image_fabric(dir, 8);
  ProcessResult r = run_cli(dir, {"inspect", f.toml});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("resolution  8 x 8"));
  EXPECT_THAT(r.out, HasSubstr("derived from the height map"));
  EXPECT_THAT(r.out, HasSubstr("bake        resolution 8"));
  EXPECT_FALSE(nlohmann::json::accept(r.out)) << "not JSON without --json";
}

TEST(CliInspect, BadInputExitsTwoWithTheMessageOnStderr) {
  ScratchDir dir;
  auto f = testing::write_image_fabric(dir, 8, "", "[bake]\nresolutoin = 8\n");
  ProcessResult r = run_cli(dir, {"inspect", f.toml, "--json"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "") << "no JSON on failure";
  EXPECT_THAT(r.err, HasSubstr("did you mean 'bake.resolution'?"));
  r = run_cli(dir, {"inspect", dir / "missing.toml"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("file not found"));
  r = run_cli(dir, {"inspect"});
  EXPECT_EQ(r.exit_code, 1) << "usage error";
}

TEST(CliInspect, ConstantHeightWarningIsInTheJson) {
  ScratchDir dir;
  auto f = testing::write_image_fabric(dir, 8);
  write_image(dir / "height.exr", testing::make_image(8, 8, 1, [](int, int, int) { return 0.0; }),
              PixelType::Float32);
  ProcessResult r = run_cli(dir, {"inspect", f.toml, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["warnings"].size(), 1u);
  EXPECT_THAT(doc["warnings"][0].get<std::string>(), HasSubstr("constant"));
  EXPECT_THAT(r.err, HasSubstr("warning"));
  EXPECT_EQ(doc["maps"]["normal"]["origin"], "derived_from_height");
  EXPECT_EQ(doc["maps"]["height"]["origin"], "file");
  EXPECT_EQ(doc["maps"]["height"]["file"], dir / "height.exr");
}

TEST(CliPattern, NamedWeaveJsonAndRoundTripThroughInspect) {
  ScratchDir dir;
  ProcessResult r = run_cli(
      dir, {"pattern", "--weave", "twill2/1", "--resolution", "24", "-o", dir / "maps", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["resolution"], 24);
  EXPECT_EQ(doc["source"], "named_weave");
  EXPECT_EQ(doc["weave"]["matrix"], nlohmann::json({"110", "011", "101"}));
  EXPECT_EQ(doc["weave"]["end_colors"].size(), 3u);
  EXPECT_EQ(doc["weave"]["pick_colors"].size(), 3u);
  EXPECT_EQ(doc["yarns"].size(), 2u);
  EXPECT_EQ(doc["yarns"][1]["color"].size(), 3u);
  EXPECT_EQ(doc["files"].size(), 13u);
  for (const auto& f : doc["files"])
    EXPECT_TRUE(fs::exists(f["path"].get<std::string>())) << f;
  for (const char* name :
       {"height.exr", "tangent.exr", "normal.exr", "gap.exr", "yarn_id.exr", "albedo.exr",
        "height.preview.png", "yarn_id.preview.png", "fabric.toml"})
    EXPECT_TRUE(fs::exists(dir / ("maps/" + std::string(name)))) << name;
  // The written fabric is valid and refers to the EXR maps.
  ProcessResult inspect = run_cli(dir, {"inspect", dir / "maps/fabric.toml", "--json"});
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  nlohmann::json idoc = nlohmann::json::parse(inspect.out);
  EXPECT_EQ(idoc["source"], "images");
  EXPECT_EQ(idoc["resolution"], 24);
  EXPECT_EQ(idoc["maps"]["tangent"]["file"], dir / "maps/tangent.exr");
  EXPECT_EQ(idoc["inputs"].size(), 7u);
  EXPECT_DOUBLE_EQ(idoc["tile"]["size_mm"].get<double>(), doc["tile_size_mm"].get<double>());
}

TEST(CliPattern, FromAFabricFileAndNotJson) {
  ScratchDir dir;
  ProcessResult r =
      run_cli(dir, {"pattern", kExamples + "diamond.toml", "--resolution", "28", "-o", dir / "d"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote 13 files"));
  EXPECT_THAT(read_text(dir / "d/fabric.toml"), HasSubstr("name = \"silk diamond point twill\""));
}

TEST(CliPattern, WifDraftJson) {
  ScratchDir dir;
  ProcessResult r = run_cli(
      dir, {"pattern", "--wif", std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/wif/twill-2-2.wif",
            "--resolution", "16", "-o", dir / "w", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["source"], "wif");
  EXPECT_EQ(doc["weave"]["matrix"].size(), doc["weave"]["picks"].get<std::size_t>());
  EXPECT_EQ(doc["weave"]["end_colors"].size(), doc["weave"]["ends"].get<std::size_t>());
  EXPECT_EQ(doc["inputs"][0]["role"], "wif");
  EXPECT_THAT(read_text(dir / "w/fabric.toml"),
              HasSubstr("Generated from the WIF draft twill-2-2.wif."));
}

TEST(CliPattern, FailuresWriteNothing) {
  ScratchDir dir;
  ProcessResult r = run_cli(dir, {"pattern", "--weave", "twil2/1", "-o", dir / "out", "--json"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_THAT(r.err, HasSubstr("twil2/1"));
  EXPECT_FALSE(fs::exists(dir / "out"));

  auto f = testing::write_image_fabric(dir, 8);
  write_image(dir / "tangent.exr", testing::make_image(8, 8, 3, [](int, int, int) { return 0.0; }),
              PixelType::Float32);
  r = run_cli(dir, {"pattern", f.toml, "-o", dir / "out2"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("pixel (0, 0) has a zero-length tangent"));
  EXPECT_FALSE(fs::exists(dir / "out2"));

  // An existing output directory is untouched by a failed run.
  fs::create_directories(dir / "keep");
  write_text(dir / "keep/mine.txt", "mine");
  r = run_cli(dir, {"pattern", f.toml, "-o", dir / "keep"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(read_text(dir / "keep/mine.txt"), "mine");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "keep"), fs::directory_iterator()), 1);
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr(".tmp-")));
}

TEST(CliPattern, UsageErrors) {
  ScratchDir dir;
  EXPECT_EQ(run_cli(dir, {"pattern", "-o", dir / "x"}).exit_code, 1) << "no source";
  EXPECT_EQ(
      run_cli(dir, {"pattern", "--weave", "plain", "--wif", "a.wif", "-o", dir / "x"}).exit_code,
      1);
  EXPECT_EQ(run_cli(dir, {"pattern", "--weave", "plain"}).exit_code, 1) << "-o is required";
  EXPECT_EQ(
      run_cli(dir, {"pattern", "--weave", "plain", "--resolution", "2", "-o", dir / "x"}).exit_code,
      1);
  EXPECT_FALSE(fs::exists(dir / "x"));
}

}  // namespace
}  // namespace clothbake

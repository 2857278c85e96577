// Hostile assets and inputs end to end through the built clothbake (docs/cli.md exit codes,
// docs/format.md validation IDs): assets crafted by editing a good one and recomputing every
// checksum (tests/support/hostile_asset.hpp), byte paths, failing stdout, special files. Every
// case asserts the documented exit code (never 4, never a signal) and that nothing is left behind.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "formats/reader/layout.hpp"
#include "tests/support/hostile_asset.hpp"
#include "tests/support/run_cli.hpp"

using namespace clothbake;
namespace fs = std::filesystem;
using reader::SectionType;
using test_support::CliRun;
using test_support::run_clothbake;
using test_support::run_clothbake_line;

namespace {

class Hardening : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("clothbake_hardening_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    Fabric fabric = fabric_from_named_weave("twill2/1", 16).fabric;
    fabric.bake.visibility_dirs = 8;
    fabric.bake.radiance_dirs = 6;
    fabric.bake.clusters = 3;
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.output_path = good();
    request.stages = {"compress"};
    pipeline::bake(request, stages::bake_stages());
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string good() { return (*dir_ / "good.cbk").string(); }
  static std::string path(const std::string& name) { return (*dir_ / name).string(); }
  // The good asset with its metadata replaced by `text`, written at dir/name.
  static std::string with_metadata(const std::string& name, const std::string& text) {
    auto sections = test_support::sections_of(good());
    test_support::section_of(sections, SectionType::Metadata) =
        test_support::raw_metadata_section(text);
    test_support::write_sections(path(name), sections);
    return path(name);
  }
  static std::string good_metadata() {
    reader::Asset a;
    EXPECT_TRUE(a.open_file(good().c_str()).ok());
    std::string_view text;
    EXPECT_TRUE(a.metadata_json(&text).ok());
    return std::string(text);
  }
  static fs::path* dir_;
};
fs::path* Hardening::dir_ = nullptr;

// A small plain-weave fabric (16 x 16, few directions: a bake takes well under a second), with
// each (from, to) replacement applied to its text.
std::string fabric_text(const std::vector<std::pair<std::string, std::string>>& edits = {}) {
  std::string text = R"(name = "small plain"
[weave]
name = "plain"
[weave.warp]
spacing_mm = 0.25
width = 0.85
height_mm = 0.12
twist_deg = 25
[weave.weft]
spacing_mm = 0.25
width = 0.85
height_mm = 0.12
twist_deg = 25
[[yarn]]
name = "warp"
roughness = 0.45
optical_thickness = 1.5
specular_albedo = 0.53
diffuse_reflectance = 0.27
diffuse_transmittance = 0.20
color = [0.30, 0.45, 0.70]
[[yarn]]
name = "weft"
roughness = 0.45
optical_thickness = 1.5
specular_albedo = 0.53
diffuse_reflectance = 0.27
diffuse_transmittance = 0.20
color = [0.30, 0.45, 0.70]
[sheen]
color = 0.20
roughness = 0.40
[bake]
resolution = 16
parallax_dirs = 8
visibility_dirs = 8
radiance_dirs = 6
clusters = 2
)";
  for (const auto& [from, to] : edits) {
    const auto at = text.find(from);
    if (at == std::string::npos) throw std::runtime_error("fabric_text: no " + from);
    text.replace(at, from.size(), to);
  }
  return text;
}

bool mentions(const CliRun& r, const std::string& what) {
  return r.err.find(what) != std::string::npos || r.out.find(what) != std::string::npos;
}

}  // namespace

// Defect 1: deep nesting used to overflow the stack in `info` (SIGSEGV) and blow up `info --json`,
// while `validate` called the asset valid.
TEST_F(Hardening, DeeplyNestedMetadataIsAnInvalidAsset) {
  const std::size_t depth = 200000;
  std::string text = R"({"format": "clothbake-asset", "x": )" + std::string(depth, '[') +
                     std::string(depth, ']') + "}";
  const std::string asset = with_metadata("deep.cbk", text);
  for (const char* command : {"info", "validate"}) {
    for (bool json : {false, true}) {
      std::vector<std::string> args{command, asset};
      if (json) args.push_back("--json");
      const CliRun r = run_clothbake(args);
      EXPECT_EQ(r.code, 3) << command << ' ' << json << ": " << r.err.substr(0, 500);
      EXPECT_TRUE(mentions(r, "CBK-E020")) << command;
      EXPECT_TRUE(mentions(r, "nested deeper than 64")) << command;
      EXPECT_LT(r.out.size(), 100000u);
    }
  }
  // 64 levels are accepted.
  text =
      R"({"format": "clothbake-asset", "x": )" + std::string(63, '[') + std::string(63, ']') + "}";
  EXPECT_EQ(run_clothbake({"validate", with_metadata("deep63.cbk", text)}).code, 0);
}

// Defect 9: metadata that is valid JSON with known keys of the wrong type made `info` exit 4.
TEST_F(Hardening, MetadataOfTheWrongTypesIsAnInvalidAssetForEveryCommand) {
  nlohmann::json good_json = nlohmann::json::parse(good_metadata());
  struct Case {
    const char* name;
    const char* key;
    nlohmann::json value;
    const char* message;
  };
  const Case cases[] = {
      {"stages", "stages", nlohmann::json::array({1}), "\"stages[0]\" is not a string"},
      {"tool", "tool", 5, "\"tool\" is not an object"},
      {"toolname", "tool", {{"name", 3}}, "\"tool.name\" is not a string"},
      {"inputs", "fabric", {{"inputs", {7}}}, "\"fabric.inputs[0]\" is not an object"},
  };
  for (const Case& c : cases) {
    nlohmann::json m = good_json;
    m[c.key] = c.value;
    const std::string asset = with_metadata(std::string(c.name) + ".cbk", m.dump(2));
    for (const char* command : {"info", "validate"}) {
      const CliRun r = run_clothbake({command, asset});
      EXPECT_EQ(r.code, 3) << c.name << ' ' << command << ": " << r.err;
      EXPECT_TRUE(mentions(r, "CBK-E023")) << c.name << ' ' << command << r.out << r.err;
      EXPECT_TRUE(mentions(r, c.message)) << c.name << ' ' << command << r.out << r.err;
    }
  }
}

// Defects 9 and 15: a yarn name that is not UTF-8 made `info --json` exit 4; terminal escape codes
// in a name were printed raw. validate rejects the first (CBK-E023); info escapes both.
TEST_F(Hardening, YarnNamesAreCheckedAndPrintedSafely) {
  for (const std::string name : {std::string("bad\xff\xfe"), std::string("\x1b[2J\x1b]0;x\a")}) {
    auto sections = test_support::sections_of(good());
    auto& yarns = test_support::section_of(sections, SectionType::YarnMaterials);
    std::memset(yarns.payload.data(), 0, 32);
    std::memcpy(yarns.payload.data(), name.data(), name.size());
    test_support::write_sections(path("yarn.cbk"), sections);
    CliRun r = run_clothbake({"info", path("yarn.cbk")});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out.find('\x1b'), std::string::npos);
    EXPECT_EQ(r.out.find('\xff'), std::string::npos);
    EXPECT_TRUE(mentions(r, name[0] == 'b' ? "bad\\xFF\\xFE" : "\\x1B[2J\\x1B]0;x\\x07")) << r.out;
    r = run_clothbake({"info", path("yarn.cbk"), "--json"});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NO_THROW((void)nlohmann::json::parse(r.out));
    r = run_clothbake({"validate", path("yarn.cbk")});
    EXPECT_EQ(r.code, name[0] == 'b' ? 3 : 0) << r.out;
    if (name[0] == 'b') EXPECT_TRUE(mentions(r, "CBK-E023"));
  }
}

// Defect 5: a non-UTF-8 output path made `bake --json` exit 4 after writing the asset, and
// info/validate/inspect --json exit 4. Paths are bytes; the JSON carries U+FFFD for such bytes.
TEST_F(Hardening, NonUtf8PathsNeverFailTheJsonOutput) {
  const std::string asset = path("out\xff.cbk");
  fs::copy_file(good(), asset, fs::copy_options::overwrite_existing);
  for (const char* command : {"info", "validate"}) {
    const CliRun r = run_clothbake({command, asset, "--json"});
    EXPECT_EQ(r.code, 0) << command << ": " << r.err;
    const auto doc = nlohmann::json::parse(r.out);
    EXPECT_EQ(doc["path"], path("out\xef\xbf\xbd.cbk"));
  }
  const std::string fabric = path("fab\xfe.toml");
  std::ofstream(fabric) << fabric_text();
  CliRun r = run_clothbake({"inspect", fabric, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NO_THROW((void)nlohmann::json::parse(r.out));
  const std::string out = path("baked\xff.cbk");
  r = run_clothbake({"bake", fabric, "-o", out, "--stages", "feature_maps", "--json", "--quiet"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NO_THROW((void)nlohmann::json::parse(r.out));
  EXPECT_TRUE(fs::exists(out));
}

// Defect 7: output lost on a full stdout used to exit 0.
TEST_F(Hardening, AFailedWriteToStdoutExits2) {
  for (const std::string command :
       {"info " + good() + " --json", "info " + good(), "validate " + good(),
        "validate " + good() + " --json",
        "query " + good() + " visibility --dir 0,0,1 --texel 1,1 --json"}) {
    const CliRun r = run_clothbake_line(command + " > /dev/full");
    EXPECT_EQ(r.code, 2) << command << ": " << r.err;
    EXPECT_NE(r.err.find("cannot write to standard output"), std::string::npos) << r.err;
  }
  EXPECT_EQ(run_clothbake_line("info " + good() + " > /dev/null").code, 0);
}

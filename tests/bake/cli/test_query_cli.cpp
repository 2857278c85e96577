// `clothbake query`: the JSON answers equal the reader library's, and every bad argument or asset
// exits with its documented code and a message naming the option or the problem.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "compress/compress_settings.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "tests/support/run_cli.hpp"

using namespace clothbake;
namespace fs = std::filesystem;

namespace {

using test_support::CliRun;

// `clothbake query ARGS` (split by the shell).
CliRun run(const std::string& args) {
  return test_support::run_clothbake_line("query " + args);
}

// One small asset with both stages, one without them, and a corrupted copy, shared by the tests.
class QueryCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ =
        new fs::path(fs::temp_directory_path() / ("clothbake_query_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    Fabric fabric = fabric_from_named_weave("twill2/1", 16).fabric;
    fabric.bake.parallax_dirs = 8;
    fabric.bake.visibility_dirs = 8;
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.output_path = asset();
    request.stages = {"parallax", "visibility"};
    compress::CompressRequest keep_raw;  // --keep-raw: with asg_fit_error (not written by default)
    keep_raw.keep_raw = true;
    request.seeds.put(stages::kCompressSettingsArtifact, keep_raw);
    pipeline::bake(request, stages::bake_stages());
    pipeline::BakeRequest bare_request;
    bare_request.fabric = fabric;
    bare_request.output_path = bare();
    bare_request.stages = {"feature_maps"};
    pipeline::bake(bare_request, stages::bake_stages());
    fs::copy_file(asset(), corrupt());
    // Flip a byte in the last section's payload (its checksum no longer matches).
    std::fstream f(corrupt(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(-100, std::ios::end);
    char c;
    f.get(c);
    f.seekp(-100, std::ios::end);
    f.put(char(c ^ 0x5a));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string asset() { return (*dir_ / "twill.cbk").string(); }
  static std::string bare() { return (*dir_ / "bare.cbk").string(); }
  static std::string corrupt() { return (*dir_ / "corrupt.cbk").string(); }
  static fs::path* dir_;
};
fs::path* QueryCli::dir_ = nullptr;

}  // namespace

TEST_F(QueryCli, ParallaxAnswersEqualTheReader) {
  reader::Asset a;
  ASSERT_TRUE(a.open_file(asset().c_str()).ok());
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(a).ok());
  const double dir[3] = {0.3, -0.2, 0.8};
  reader::ParallaxSample s;
  ASSERT_TRUE(view.depth(3, 17, dir, &s).ok());  // 17 wraps to 1
  CliRun r = run(asset() + " parallax --dir 0.3,-0.2,0.8 --texel 3,17 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["r"].get<double>(), s.r);
  EXPECT_EQ(j["offset_tile"][0].get<double>(), s.offset[0]);
  EXPECT_EQ(j["offset_texels"][1].get<double>(), s.offset[1] * 16);
  EXPECT_EQ(j["resolution"], 16);
  EXPECT_FALSE(j["clamped_to_cap"].get<bool>());

  ASSERT_TRUE(view.footprint_depth({-2.5, 1, 30, 4.25}, dir, &s).ok());
  r = run(asset() + " parallax --dir 0.3,-0.2,0.8 --rect=-2.5,1,30,4.25 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["r"].get<double>(), s.r);

  r = run(asset() + " parallax --dir 1,0,0.1 --texel 0,0 --json");  // below the cap
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["clamped_to_cap"].get<bool>());
  r = run(asset() + " parallax --dir 0,0,1 --texel 2,2");  // human-readable form
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("r = "), std::string::npos);
}

TEST_F(QueryCli, VisibilityAnswersEqualTheReader) {
  reader::Asset a;
  ASSERT_TRUE(a.open_file(asset().c_str()).ok());
  reader::VisibilityAsgView view;
  ASSERT_TRUE(view.open(a).ok());
  const double dir[3] = {-0.4, 0.1, 0.5};
  double v;
  ASSERT_TRUE(view.visibility(5, 9, dir, &v).ok());
  CliRun r = run(asset() + " visibility --texel 5,9 --dir -0.4,0.1,0.5 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["visibility"].get<double>(), v);
  EXPECT_EQ(j["asg"]["lambda"].get<double>(), view.lobe(5, 9).lambda);
  EXPECT_EQ(j["fit_error"].get<double>(), view.fit_error(5, 9));
}

TEST_F(QueryCli, BadArgumentsExitOneNamingTheOption) {
  struct Case {
    std::string args, option;
  };
  const Case cases[] = {
      {" parallax --texel 1,1", "--dir"},
      {" parallax --dir 0,0,1", "--texel"},
      {" parallax --dir 0,0,1 --texel 1,1 --rect 0,0,1,1", "--texel"},
      {" parallax --dir 0,0,1 --texel 1,a", "--texel"},
      {" parallax --dir 0,0,1 --texel 1", "--texel"},
      {" parallax --dir 0,0,1 --rect 2,0,1,1", "--rect"},
      // The commands' own checks point at the options too, as CLI11's refusals do.
      {" parallax --dir 0,0,1 --rect 2,0,1,1",
       "(clothbake query parallax --help lists the options)"},
      {" parallax --dir 0,0,0 --texel 1,1", "--dir"},
      {" parallax --dir 0,nan,1 --texel 1,1", "--dir"},
      {" visibility --dir 0,0,1", "--texel"},
      {" visibility --texel 1,1", "--dir"},
      // An option of another kind is unknown to this one, named with where the options are.
      {" visibility --dir 0,0,1 --texel 1,1 --rect 0,0,1,1", "--rect"},
      {" visibility --dir 0,0,1 --texel 1,1 --rect 0,0,1,1", "query visibility --help"},
      {" radiance --dir 0,0,1 --texel 1,1", "--dir"},
      {" parallax --dir 0,0,1 --texel 1,1 --lobe specular_reflection", "--lobe"},
      {" radiance --h 0,0,1 --rect 0,0,1,1", "--lobe"},  // radiance needs a lobe
      {" hologram --dir 0,0,1", "query needs one of parallax, visibility or radiance"},
  };
  for (const Case& c : cases) {
    CliRun r = run(asset() + c.args);
    EXPECT_EQ(r.code, 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.option), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << c.args;
  }
}

TEST_F(QueryCli, MissingFilesAndSectionsExitTwoCorruptAssetsExitThree) {
  CliRun r = run((*dir_ / "absent.cbk").string() + " parallax --dir 0,0,1 --texel 1,1");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("absent.cbk"), std::string::npos) << r.err;
  r = run(bare() + " parallax --dir 0,0,1 --texel 1,1");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no parallax table"), std::string::npos) << r.err;
  r = run(bare() + " visibility --dir 0,0,1 --texel 1,1");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no visibility"), std::string::npos) << r.err;
  r = run(corrupt() + " parallax --dir 0,0,1 --texel 1,1");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("CBK-E012"), std::string::npos) << r.err;
}

// In-process bakes through the fabric and write stages with a programmatic fabric: the asset is
// valid and holds the fabric, bytes are identical for any thread count and run to run, the report
// has the documented fields, and a failing bake writes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/validate/validate.hpp"
#include "raycast/heightfield_scene.hpp"
#include "tests/formats/test_fabric.hpp"

namespace {

using namespace clothbake;
namespace fs = std::filesystem;

// The stages that encode the fabric and write it (no ray casting, tables or compression): what
// these tests bake, quickly, with "all stages".
std::vector<pipeline::Stage> fabric_and_write_stages() {
  return {stages::load_fabric_stage(), stages::fabric_records_stage(), stages::feature_maps_stage(),
          stages::write_stage()};
}

class Bake : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake-bake-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  pipeline::BakeResult bake(const std::string& name, int threads, int n = 64,
                            std::vector<std::string> stages = {}) {
    pipeline::BakeRequest request;
    request.fabric = test_support::make_test_fabric(n);
    request.output_path = (dir_ / name).string();
    request.run.threads = threads;
    request.stages = std::move(stages);
    return pipeline::bake(request, fabric_and_write_stages());
  }
  std::string read(const std::string& name) {
    std::ifstream in(dir_ / name, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  fs::path dir_;
};

TEST_F(Bake, WritesAValidAssetWithTheFabric) {
  const auto result = bake("a.cbk", 0);
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file((dir_ / "a.cbk").c_str()).ok());
  EXPECT_EQ(reader::validate_asset(asset, nullptr, nullptr).errors, 0u);
  reader::FeatureMaps maps;
  ASSERT_TRUE(reader::read_feature_maps(asset, &maps).ok());
  EXPECT_EQ(maps.resolution, 64u);
  const Fabric fabric = test_support::make_test_fabric(64);
  for (std::size_t t = 0; t < fabric.maps.texel_count(); ++t)
    ASSERT_EQ(maps.height[t], fabric.maps.height[t]);
  std::string_view text;
  ASSERT_TRUE(asset.metadata_json(&text).ok());
  const auto metadata = nlohmann::json::parse(text);
  EXPECT_EQ(metadata["format"], "clothbake-asset");
  EXPECT_EQ(metadata["fabric"]["inputs"][0]["xxh64"], "0123456789abcdef");
  EXPECT_EQ(metadata["stages"], nlohmann::json({"fabric_records", "feature_maps", "write"}));
  EXPECT_FALSE(metadata.contains("timings"));
  EXPECT_EQ(result.asset.size_bytes, fs::file_size(dir_ / "a.cbk"));
  EXPECT_EQ(result.asset.sections.size(), asset.section_count());
}

TEST_F(Bake, BytesAreIdenticalForAnyThreadCountAndRunToRun) {
  bake("t1.cbk", 1, 256);
  bake("t2.cbk", 2, 256);
  bake("t2-again.cbk", 2, 256);
  bake("default.cbk", 0, 256);
  const std::string reference = read("t1.cbk");
  ASSERT_GT(reference.size(), 256u * 256u * 4u);
  EXPECT_EQ(read("t2.cbk"), reference);
  EXPECT_EQ(read("t2-again.cbk"), reference);
  EXPECT_EQ(read("default.cbk"), reference);
}

TEST_F(Bake, StagesSelectWhatGoesIntoTheAsset) {
  const auto result = bake("records.cbk", 0, 16, {"fabric_records"});
  std::vector<std::string> names;
  for (const auto& s : result.asset.sections)
    names.push_back(s.name);
  EXPECT_EQ(names, (std::vector<std::string>{"metadata", "fabric_info", "yarn_materials"}));
  try {
    bake("x.cbk", 0, 16, {"no_such_stage"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Usage);
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.cbk"));
}

TEST_F(Bake, ReportHasTheDocumentedFields) {
  pipeline::BakeRequest request;
  request.fabric = test_support::make_test_fabric(32);
  request.output_path = (dir_ / "r.cbk").string();
  request.run.threads = 2;
  const auto result = pipeline::bake(request, fabric_and_write_stages());
  const nlohmann::json report = pipeline::bake_report_json(request, result);
  EXPECT_EQ(report["threads"], 2);
  ASSERT_EQ(report["stages"].size(), 3u);
  for (const auto& s : report["stages"]) {
    EXPECT_TRUE(s.contains("name"));
    EXPECT_GE(s["wall_seconds"].get<double>(), 0.0);
    EXPECT_GE(s["cpu_seconds"].get<double>(), 0.0);
    EXPECT_GT(s["peak_rss_bytes"].get<uint64_t>(), 0u);
  }
  EXPECT_EQ(report["asset"]["size_bytes"], fs::file_size(dir_ / "r.cbk"));
  EXPECT_EQ(report["asset"]["content_hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(report["asset"]["sections"].size(), 9u);
}

TEST_F(Bake, RecordedTimingsAreOptIn) {
  pipeline::BakeRequest request;
  request.fabric = test_support::make_test_fabric(8);
  request.output_path = (dir_ / "timed.cbk").string();
  request.run.record_timings = true;
  pipeline::bake(request, fabric_and_write_stages());
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(request.output_path.c_str()).ok());
  std::string_view text;
  ASSERT_TRUE(asset.metadata_json(&text).ok());
  const auto metadata = nlohmann::json::parse(text);
  ASSERT_TRUE(metadata.contains("timings"));
  EXPECT_EQ(metadata["timings"].size(), 2u);  // the stages before write
}

TEST_F(Bake, BadFabricWritesNothingAndKeepsThePreviousAsset) {
  bake("keep.cbk", 0, 8);
  const std::string previous = read("keep.cbk");
  pipeline::BakeRequest request;
  request.fabric = test_support::make_test_fabric(8);
  request.fabric->maps.height[9] = std::numeric_limits<float>::quiet_NaN();
  request.output_path = (dir_ / "keep.cbk").string();
  try {
    pipeline::bake(request, fabric_and_write_stages());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("height element 9 [1, 1] is NaN"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read("keep.cbk"), previous);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(Bake, BadOutputFailsBeforeAnyWork) {
  pipeline::BakeRequest request;
  request.fabric_path = "/nonexistent/fabric.toml";  // never read: the output is checked first
  request.output_path = dir_.string();
  try {
    pipeline::bake(request, fabric_and_write_stages());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
}

}  // namespace

namespace {

// A 16^2 test fabric whose relief is amplitude * sin(2 pi u) (tile units), with small direction
// grids, as `report stability` bakes its relief cases.
Fabric sine_relief_fabric(double amplitude) {
  Fabric f = test_support::make_test_fabric(16, "sine-relief");
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      f.maps.height[f.maps.index(x, y)] = float(amplitude * std::sin(2 * M_PI * (x + 0.5) / 16));
  f.bake.parallax_dirs = f.bake.visibility_dirs = f.bake.radiance_dirs = 8;
  f.bake.clusters = 2;
  return f;
}

// The child of the test below: whole bakes in one process, flat, low (rings = 0: rays cast into a
// scene without instances, coherent first hits and incoherent occlusion) and tall (rings 3:
// instanced) fabrics in turn.
[[noreturn]] void bake_low_and_tall(const std::string& dir) {
  ::alarm(60);
  set_quiet(true);
  for (double amplitude : {0.0, 1.0, 0.05, 1.0, 0.05, 0.05, 1.0}) {
    pipeline::BakeRequest request;
    request.fabric = sine_relief_fabric(amplitude);
    request.output_path = dir + "/relief-" + std::to_string(amplitude) + ".cbk";
    pipeline::bake(request, stages::bake_stages());
  }
  // The child exits here, so its fixture's TearDown never runs: it removes its own directory.
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  std::exit(0);
}

}  // namespace

// Several bakes in one process (`report stability`, scenes that bake fabrics on the fly, tests):
// after a fabric whose height field needs no neighbour tiles, the visibility stage of a tall one
// never returned on AVX-512 machines, inside Embree's coherent packet kernel (docs/hardening.md,
// "The Embree hang"). In a fresh child process under a 60 s alarm, so that a hang fails the test.
TEST_F(Bake, LowAndTallFabricsInOneProcessAllFinish) {
  ASSERT_EQ(raycast::automatic_rings(0.1), 0);  // amplitude 0.05: no neighbour tiles
  ASSERT_GE(raycast::automatic_rings(2.0), 1);  // amplitude 1: instanced
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(bake_low_and_tall(dir_.string()), ::testing::ExitedWithCode(0), "");
}

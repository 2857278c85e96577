// The table fit behind `clothbake fit-sheen` (sheen/sheen_fit.hpp, sheen_table_writer.hpp):
// determinism across thread counts, the header format, reproduction of the committed table's
// albedos, atomic writing, and the CLI's error handling.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "common/error.hpp"
#include "model/sheen_table.hpp"
#include "sheen/sheen_fit.hpp"
#include "sheen/sheen_table_writer.hpp"
#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;
using namespace clothbake::sheen;

namespace {

SheenFitSettings tiny_settings() {
  SheenFitSettings s;
  s.cos_count = 3;
  s.roughness_count = 3;
  s.paths_per_node = 20000;
  s.min_reflected = 500;
  s.binning = ExitBinning{16, 16};
  return s;
}

const SheenTableFit& tiny_fit() {
  static const SheenTableFit fit = fit_sheen_table(tiny_settings());
  return fit;
}

std::vector<float> table_literals(const std::string& header) {
  const std::string body = header.substr(header.find("kTable["));
  std::vector<float> values;
  const std::regex literal(R"((-?[0-9][0-9.e+-]*)f\b)");
  for (auto it = std::sregex_iterator(body.begin(), body.end(), literal);
       it != std::sregex_iterator(); ++it)
    values.push_back(std::stof((*it)[1].str()));
  return values;
}

TEST(SheenFit, SameBytesForOneAndTwoThreads) {
  std::string one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = format_sheen_table_header(fit_sheen_table(tiny_settings()));
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = format_sheen_table_header(fit_sheen_table(tiny_settings()));
  }
  EXPECT_EQ(one, two);
  SheenFitSettings other = tiny_settings();
  other.seed = 2;
  EXPECT_NE(format_sheen_table_header(fit_sheen_table(other)), one);
}

TEST(SheenFit, NodesFollowTheDocumentedLayout) {
  const SheenTableFit& fit = tiny_fit();
  ASSERT_EQ(fit.nodes.size(), 9u);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const SheenTableNode& n = fit.at(i, j);
      EXPECT_DOUBLE_EQ(n.cos_theta, i / 2.0);
      EXPECT_DOUBLE_EQ(n.roughness, j / 2.0);
      EXPECT_DOUBLE_EQ(n.simulated_cos, i == 0 ? tiny_settings().min_simulated_cos : i / 2.0);
      EXPECT_GT(n.a, 0.0);
      EXPECT_EQ(n.truncated, 0u);
    }
  // Roughness 0 reflects nothing, so its shape is inherited from roughness 0.5.
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(fit.at(i, 0).albedo, 0.0);
    EXPECT_TRUE(fit.at(i, 0).inherited_shape);
    EXPECT_EQ(fit.at(i, 0).a, fit.at(i, 1).a);
  }
  // The pole row keeps b = 0.
  for (int j = 0; j < 3; ++j)
    EXPECT_EQ(fit.at(2, j).b, 0.0);
}

TEST(SheenFit, HeaderHoldsTheNodesAsExactFloats) {
  const SheenTableFit& fit = tiny_fit();
  const std::string header = format_sheen_table_header(fit);
  EXPECT_NE(header.find("inline constexpr int kCosCount = 3;"), std::string::npos);
  EXPECT_NE(header.find("inline constexpr int kRoughnessCount = 3;"), std::string::npos);
  EXPECT_NE(header.find("kPathsPerNode = 20000ull;"), std::string::npos);
  EXPECT_NE(header.find("--samples 20000 --resolution 3,3 --seed 1"), std::string::npos);
  const std::vector<float> values = table_literals(header);
  ASSERT_EQ(values.size(), 27u);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const SheenTableNode& n = fit.at(i, j);
      const std::size_t k = std::size_t(3 * (3 * j + i));
      EXPECT_EQ(values[k], float(n.a));
      EXPECT_EQ(values[k + 1], float(n.b));
      EXPECT_EQ(values[k + 2], float(n.albedo));
    }
}

// The committed model/sheen_table.hpp was written by this code: re-simulating a node with the
// table's seed and the node's stream reproduces its R to the last bit.
TEST(SheenFit, CommittedTableAlbedosAreReproducible) {
  namespace table = clothbake::model::sheen_table;
  const int last_cos = table::kCosCount - 1, last_rough = table::kRoughnessCount - 1;
  for (auto [i, j] : {std::array<int, 2>{last_cos, last_rough}, {last_cos / 2, last_rough}}) {
    LayerSimulationSettings s;
    s.paths = table::kPathsPerNode;
    s.seed = table::kSeed;
    s.stream = uint64_t(j * table::kCosCount + i);
    s.histogram = false;
    const double mu = std::max(double(i) / last_cos, table::kMinSimulatedCos);
    const LayerSimulation sim = simulate_sheen_layer(mu, double(j) / last_rough, s);
    EXPECT_EQ(float(sim.albedo()), table::kTable[j][i][2]) << "node " << i << "," << j;
  }
}

TEST(SheenFit, RejectsInvalidSettings) {
  SheenFitSettings s = tiny_settings();
  s.cos_count = 1;
  EXPECT_THROW(validate(s), std::invalid_argument);
  s = tiny_settings();
  s.paths_per_node = 10;
  EXPECT_THROW(validate(s), std::invalid_argument);
  s = tiny_settings();
  s.binning.z_bins = 0;
  EXPECT_THROW(validate(s), std::invalid_argument);
  s = tiny_settings();
  s.min_simulated_cos = 0.0;
  EXPECT_THROW(validate(s), std::invalid_argument);
}

fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::path(CLOTHBAKE_BINARY_DIR) / "test-scratch" / "sheen" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(SheenFit, WritesAtomicallyAndReportsTheFailingPath) {
  const fs::path dir = scratch_dir("atomic");
  const fs::path target = dir / "table.hpp";
  write_file_atomically(target.string(), "first\n");
  write_file_atomically(target.string(), "second\n");
  std::ifstream in(target);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "second\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);

  const std::string missing = (dir / "no-such-dir" / "table.hpp").string();
  try {
    write_file_atomically(missing, "x");
    FAIL() << "expected an error";
  } catch (const clothbake::Error& e) {
    EXPECT_EQ(e.code(), clothbake::ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_file_atomically(dir.string(), "x"), clothbake::Error);  // a directory
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

// --- the CLI ------------------------------------------------------------------------------------

using clothbake::test_support::CliRun;

// `clothbake ARGS` (split by the shell); `dir` is unused (the command names its own outputs).
CliRun run_clothbake(const std::string& args, const fs::path& /*dir*/) {
  return clothbake::test_support::run_clothbake_line(args);
}

class FitSheenCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(fs::path(CLOTHBAKE_BINARY_DIR) / "bin" / "clothbake"))
      GTEST_SKIP() << "the clothbake executable is not built";
    dir_ = scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  fs::path dir_;
};

TEST_F(FitSheenCli, WritesTheHeaderAndAJsonReport) {
  const fs::path out = dir_ / "table.hpp";
  const CliRun run = run_clothbake(
      "fit-sheen --resolution 2,3 --samples 3000 --seed 5 --json -o " + out.string(), dir_);
  ASSERT_EQ(run.code, 0) << run.err;
  const auto doc = nlohmann::json::parse(run.out);
  EXPECT_EQ(doc["cos_count"], 2);
  EXPECT_EQ(doc["roughness_count"], 3);
  EXPECT_EQ(doc["nodes"].size(), 6u);
  EXPECT_EQ(doc["output"], out.string());
  ASSERT_TRUE(fs::exists(out));
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("kCosCount = 2;"), std::string::npos);
  EXPECT_EQ(table_literals(text.str()).size(), 18u);
}

TEST_F(FitSheenCli, BadOptionsAreUsageErrors) {
  for (const char* args :
       {"fit-sheen --resolution 1,3", "fit-sheen --resolution 4", "fit-sheen --resolution 4,x",
        "fit-sheen --samples 5", "fit-sheen --threads -1", "fit-sheen --bogus"}) {
    const CliRun run = run_clothbake(args, dir_);
    EXPECT_EQ(run.code, 1) << args << ": " << run.err;
    EXPECT_TRUE(run.out.empty()) << args;
  }
}

TEST_F(FitSheenCli, UnwritableOutputIsAnInputErrorAndWritesNothing) {
  const fs::path out = dir_ / "missing" / "table.hpp";
  const CliRun run =
      run_clothbake("fit-sheen --resolution 2,2 --samples 200 -o " + out.string(), dir_);
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find(out.string()), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir_ / "missing"));
}

}  // namespace

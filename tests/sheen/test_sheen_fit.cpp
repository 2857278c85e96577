// The table fit behind `clothbake fit-sheen` (sheen/sheen_fit.hpp, sheen_table_writer.hpp):
// determinism across thread counts, the header format of both conventions, reproduction of the
// committed tables' albedos under their rules, atomic writing, and the CLI's error handling.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "model/sheen_table.hpp"
#include "model/sheen_table_converged.hpp"
#include "sheen/sheen_fit.hpp"
#include "sheen/sheen_table_writer.hpp"
#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;
using namespace clothbake::sheen;
using clothbake::model::SheenConvention;

namespace {

SheenFitSettings tiny_settings(SheenConvention convention = SheenConvention::Published) {
  SheenFitSettings s;
  s.convention = convention;
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

const SheenTableFit& tiny_converged_fit() {
  static const SheenTableFit fit = fit_sheen_table(tiny_settings(SheenConvention::Converged));
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

TEST(SheenFit, DefaultConventionIsPublished) {
  EXPECT_EQ(SheenFitSettings().convention, SheenConvention::Published);
  const SheenSimulationRules p = simulation_rules(SheenConvention::Published);
  EXPECT_EQ(p.max_order, 16);
  EXPECT_TRUE(p.classify_by_last_direction);
  EXPECT_EQ(p.min_cos, 0.01);
  EXPECT_EQ(p.min_roughness, 0.01);
  const SheenSimulationRules c = simulation_rules(SheenConvention::Converged);
  EXPECT_FALSE(c.classify_by_last_direction);
  EXPECT_EQ(c.min_cos, 1e-3);
  EXPECT_EQ(c.min_roughness, 0.0);
  EXPECT_THROW(simulation_rules(SheenConvention(7)), std::invalid_argument);
}

TEST(SheenFit, NodesFollowTheDocumentedLayout) {
  const SheenTableFit& fit = tiny_converged_fit();
  ASSERT_EQ(fit.nodes.size(), 9u);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const SheenTableNode& n = fit.at(i, j);
      EXPECT_DOUBLE_EQ(n.cos_theta, i / 2.0);
      EXPECT_DOUBLE_EQ(n.roughness, j / 2.0);
      EXPECT_DOUBLE_EQ(n.simulated_cos, i == 0 ? 1e-3 : i / 2.0);
      EXPECT_DOUBLE_EQ(n.simulated_roughness, j / 2.0);
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

// The published rules: cos theta_o and roughness simulated at >= 0.01, paths cut after 16 events
// (at roughness 0.5 and grazing incidence some paths are that long), and the same layout.
TEST(SheenFit, PublishedRulesClampAndCut) {
  const SheenTableFit& fit = tiny_fit();
  ASSERT_EQ(fit.nodes.size(), 9u);
  uint64_t cut = 0;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const SheenTableNode& n = fit.at(i, j);
      EXPECT_DOUBLE_EQ(n.simulated_cos, i == 0 ? 0.01 : i / 2.0);
      EXPECT_DOUBLE_EQ(n.simulated_roughness, j == 0 ? 0.01 : j / 2.0);
      EXPECT_GT(n.a, 0.0);
      EXPECT_LE(n.mean_scattering_order, 16.0);
      cut += n.truncated;
    }
  EXPECT_GT(cut, 0u);
  // Roughness 0.01 reflects almost nothing at steep incidence.
  EXPECT_LT(fit.at(2, 0).albedo, 1e-3);
  // Rough sheen at steep incidence: paths are short, both rules agree within the noise.
  const SheenTableNode &p = fit.at(2, 2), &c = tiny_converged_fit().at(2, 2);
  EXPECT_NEAR(p.albedo, c.albedo,
              4.0 * std::hypot(p.albedo_standard_error, c.albedo_standard_error));
}

TEST(SheenFit, HeaderHoldsTheNodesAsExactFloats) {
  const SheenTableFit& fit = tiny_fit();
  const std::string header = format_sheen_table_header(fit);
  EXPECT_NE(header.find("inline constexpr int kCosCount = 3;"), std::string::npos);
  EXPECT_NE(header.find("inline constexpr int kRoughnessCount = 3;"), std::string::npos);
  EXPECT_NE(header.find("kPathsPerNode = 20000ull;"), std::string::npos);
  EXPECT_NE(header.find("--convention published -o model/sheen_table.hpp --samples 20000 "
                        "--resolution 3,3 --seed 1"),
            std::string::npos);
  EXPECT_NE(header.find("namespace clothbake::model::sheen_table {"), std::string::npos);
  EXPECT_NE(header.find("kMaxScatteringOrder = 16;"), std::string::npos);
  EXPECT_NE(header.find("kClassifiedByLastDirection = true;"), std::string::npos);
  EXPECT_NE(header.find("kMinSimulatedRoughness = 0.01;"), std::string::npos);
  const std::string converged = format_sheen_table_header(tiny_converged_fit());
  EXPECT_NE(converged.find("--convention converged -o model/sheen_table_converged.hpp"),
            std::string::npos);
  EXPECT_NE(converged.find("namespace clothbake::model::sheen_table_converged {"),
            std::string::npos);
  EXPECT_NE(converged.find("kClassifiedByLastDirection = false;"), std::string::npos);
  EXPECT_NE(converged.find("kMinSimulatedCos = 0.001;"), std::string::npos);
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

// The committed tables were written by this code: re-simulating a node with the table's seed, the
// node's stream and the table's rules reproduces its R to the last bit.
template <class Table>
void expect_reproducible(const std::vector<std::array<int, 2>>& nodes_ij) {
  const int last_cos = Table::kCosCount - 1, last_rough = Table::kRoughnessCount - 1;
  for (auto [i, j] : nodes_ij) {
    LayerSimulationSettings s;
    s.paths = Table::kPathsPerNode;
    s.seed = Table::kSeed;
    s.stream = uint64_t(j * Table::kCosCount + i);
    s.histogram = false;
    s.max_order = Table::kMaxScatteringOrder;
    s.classify_by_last_direction = Table::kClassifiedByLastDirection;
    const double mu = std::max(double(i) / last_cos, Table::kMinSimulatedCos);
    const double roughness = std::max(double(j) / last_rough, Table::kMinSimulatedRoughness);
    const LayerSimulation sim = simulate_sheen_layer(mu, roughness, s);
    EXPECT_EQ(float(sim.albedo()), Table::kTable[j][i][2]) << "node " << i << "," << j;
  }
}

struct PublishedTable {
  static constexpr int kCosCount = clothbake::model::sheen_table::kCosCount;
  static constexpr int kRoughnessCount = clothbake::model::sheen_table::kRoughnessCount;
  static constexpr unsigned long long kPathsPerNode = clothbake::model::sheen_table::kPathsPerNode;
  static constexpr unsigned long long kSeed = clothbake::model::sheen_table::kSeed;
  static constexpr int kMaxScatteringOrder = clothbake::model::sheen_table::kMaxScatteringOrder;
  static constexpr bool kClassifiedByLastDirection =
      clothbake::model::sheen_table::kClassifiedByLastDirection;
  static constexpr double kMinSimulatedCos = clothbake::model::sheen_table::kMinSimulatedCos;
  static constexpr double kMinSimulatedRoughness =
      clothbake::model::sheen_table::kMinSimulatedRoughness;
  static constexpr const auto& kTable = clothbake::model::sheen_table::kTable;
};
struct ConvergedTable {
  static constexpr int kCosCount = clothbake::model::sheen_table_converged::kCosCount;
  static constexpr int kRoughnessCount = clothbake::model::sheen_table_converged::kRoughnessCount;
  static constexpr unsigned long long kPathsPerNode =
      clothbake::model::sheen_table_converged::kPathsPerNode;
  static constexpr unsigned long long kSeed = clothbake::model::sheen_table_converged::kSeed;
  static constexpr int kMaxScatteringOrder =
      clothbake::model::sheen_table_converged::kMaxScatteringOrder;
  static constexpr bool kClassifiedByLastDirection =
      clothbake::model::sheen_table_converged::kClassifiedByLastDirection;
  static constexpr double kMinSimulatedCos =
      clothbake::model::sheen_table_converged::kMinSimulatedCos;
  static constexpr double kMinSimulatedRoughness =
      clothbake::model::sheen_table_converged::kMinSimulatedRoughness;
  static constexpr const auto& kTable = clothbake::model::sheen_table_converged::kTable;
};

TEST(SheenFit, CommittedConvergedTableAlbedosAreReproducible) {
  expect_reproducible<ConvergedTable>({{31, 31}, {15, 31}});
}

// (0, 1) is the node where the published rules matter most (paths cut after 16 events).
TEST(SheenFit, CommittedPublishedTableAlbedosAreReproducible) {
  expect_reproducible<PublishedTable>({{31, 31}, {0, 1}});
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
  s.convention = SheenConvention(7);
  EXPECT_THROW(validate(s), std::invalid_argument);
}

fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::path(CLOTHBAKE_BINARY_DIR) / "test-scratch" / "sheen" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
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
  EXPECT_EQ(doc["convention"], "published");
  EXPECT_EQ(doc["max_scattering_order"], 16);
}

TEST_F(FitSheenCli, ConvergedConventionWritesTheConvergedHeader) {
  const CliRun run =
      run_clothbake("fit-sheen --convention converged --resolution 2,2 --samples 500", dir_);
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("namespace clothbake::model::sheen_table_converged {"), std::string::npos);
  EXPECT_NE(run.out.find("--convention converged"), std::string::npos);
}

TEST_F(FitSheenCli, BadOptionsAreUsageErrors) {
  for (const char* args :
       {"fit-sheen --resolution 1,3", "fit-sheen --resolution 4", "fit-sheen --resolution 4,x",
        "fit-sheen --samples 5", "fit-sheen --threads -1", "fit-sheen --bogus",
        "fit-sheen --convention zeltner", "fit-sheen --convention"}) {
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

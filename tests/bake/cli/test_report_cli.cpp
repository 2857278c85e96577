// `clothbake report` through the executable: `report stability` whole (its files, --json, every
// row finite, a flat field's parallax exactly 0), `report compression` on a small tile (texel and
// raw rows only; the whole-SAT layout is a study, benchmarks/compress) and the exit codes of usage
// and output errors (the reports' parts are tested in process: tests/bake/reports).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;
using clothbake::test_support::run_clothbake;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("clothbake_report_cli_" + std::to_string(::getpid()) + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST(ReportCli, StabilityWritesFiniteRowsAndFlatParallaxIsExactlyZero) {
  const fs::path dir = scratch("stability");
  const fs::path out = dir / "report";
  const auto run = run_clothbake({"report", "stability", "-o", out.string(), "--json"});
  ASSERT_EQ(run.code, 0) << run.out << run.err;
  ASSERT_TRUE(fs::is_regular_file(out / "stability.csv"));
  ASSERT_TRUE(fs::is_regular_file(out / "stability.json"));
  EXPECT_FALSE(fs::exists(dir / "report.tmp-report"));
  std::ifstream in(out / "stability.json");
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc, nlohmann::json::parse(run.out));  // --json prints what the file holds
  ASSERT_TRUE(doc["rows"].is_array());
  std::set<std::string> cases;
  int flat_parallax = 0, table_rows = 0;
  for (const auto& r : doc["rows"]) {
    const std::string what = r["case"].get<std::string>() + " " +
                             r["parameter"].get<std::string>() + " " +
                             r["quantity"].get<std::string>();
    cases.insert(r["case"].get<std::string>());
    EXPECT_EQ(r["n_nonfinite"], 0) << what;
    EXPECT_TRUE(r["max_abs_error"].is_number()) << what;
    EXPECT_TRUE(r["max_rel_error"].is_number()) << what;
    EXPECT_TRUE(r["pass"].get<bool>()) << what;
    if (r["case"] == "flat" && r["quantity"].get<std::string>().rfind("parallax", 0) == 0) {
      EXPECT_EQ(r["max_abs_error"].get<double>(), 0.0) << what;
      EXPECT_GT(r["n_queries"].get<int>(), 1000) << what;
      ++flat_parallax;
    }
    if (r["case"] == "table") ++table_rows;
  }
  EXPECT_EQ(flat_parallax, 4);  // depth and footprint, raw and compressed
  EXPECT_GT(table_rows, 3);
  for (const char* c : {"sggx", "spongecake", "sheen", "cloth_bsdf", "flat", "relief", "table"})
    EXPECT_TRUE(cases.count(c)) << c;
  // The amplitude at the accepted maximum (+-64 tile widths) was baked and queried.
  bool max_height = false;
  for (const auto& r : doc["rows"])
    max_height |= r["case"] == "relief" && r["parameter"] == "amplitude=64";
  EXPECT_TRUE(max_height);
  // The CSV has the same rows.
  std::ifstream csv(out / "stability.csv");
  std::string line;
  int lines = 0;
  while (std::getline(csv, line))
    ++lines;
  EXPECT_EQ(lines, int(doc["rows"].size()) + 1);
}

TEST(ReportCli, CompressionWritesTexelAndRawRowsOnly) {
  const fs::path dir = scratch("compression");
  const fs::path out = dir / "report";
  const std::string fabric = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/plain.toml";
  const std::vector<std::string> args = {"report",     "compression",  fabric, "-o",
                                         out.string(), "--resolution", "16",   "--clusters",
                                         "1",          "--ranks",      "2",    "--targets",
                                         "0.02",       "--samples",    "10",   "--no-plots"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> all = args;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  // The options of the whole-SAT rows are gone: unknown options, nothing written.
  for (const auto& extra :
       std::vector<std::vector<std::string>>{{"--no-sat"}, {"--sat-resolution", "16"}}) {
    const auto refused = run_clothbake(with(extra));
    EXPECT_EQ(refused.code, 1) << extra[0] << ": " << refused.err;
    EXPECT_FALSE(fs::exists(out)) << extra[0];
  }
  const auto run = run_clothbake(with({"--json"}));
  ASSERT_EQ(run.code, 0) << run.out << run.err;
  const nlohmann::json doc = nlohmann::json::parse(run.out);
  EXPECT_EQ(doc["resolution"], 16);
  EXPECT_FALSE(doc.contains("sat_resolution"));
  std::multiset<std::string> layouts;
  for (const auto& r : doc["rows"]) {
    layouts.insert(r["layout"].get<std::string>());
    EXPECT_EQ(r["resolution"], 16);
  }
  // raw, texel k=1 r=2, texel target 0.02.
  EXPECT_EQ(layouts, (std::multiset<std::string>{"raw", "texel", "texel"}));
  // The CSV keeps its columns (the study's rows use the same ones) and has the same rows.
  std::ifstream csv(out / "compression.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line,
            "layout,normalisation,mode,resolution,clusters,rank,target,images,stored_bytes,"
            "raw_float_bytes,ratio,decoded_bytes,texel_error,normalised_mse,fp_1,fp_2,fp_4,fp_8,"
            "fp_16,fp_64,fp_tile,fp_3tiles,query_ns,compress_cpu_s,compress_wall_s,paper_point");
  int rows = 0;
  while (std::getline(csv, line))
    ++rows;
  EXPECT_EQ(rows, 3);
  fs::remove_all(dir);
}

TEST(ReportCli, UsageAndOutputErrors) {
  const fs::path dir = scratch("errors");
  // An argument stability does not take, and plan without its scene: usage errors, nothing written.
  auto run = clothbake::test_support::run_clothbake(
      {"report", "stability", "fabric.toml", "-o", (dir / "r").string()});
  EXPECT_EQ(run.code, 1) << run.err;
  EXPECT_FALSE(fs::exists(dir / "r"));
  run = clothbake::test_support::run_clothbake({"report", "plan", "-o", (dir / "r").string()});
  EXPECT_EQ(run.code, 1) << run.err;
  // An output that is a file: exit 2.
  std::ofstream(dir / "file") << "x";
  run = clothbake::test_support::run_clothbake(
      {"report", "stability", "-o", (dir / "file").string()});
  EXPECT_EQ(run.code, 2) << run.err;
  // A library's refusal of an option value reads like the parser's: it names where the options
  // are listed.
  run = clothbake::test_support::run_clothbake(
      {"report", "error-time", "scene.toml", "-o", (dir / "e").string(), "--methods", "fast"});
  EXPECT_EQ(run.code, 1) << run.err;
  EXPECT_NE(run.err.find("--methods: unknown method 'fast'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("(clothbake report error-time --help lists the options)"),
            std::string::npos)
      << run.err;
  fs::remove_all(dir);
}

// The stability report (bake/reports/report_stability.hpp), in process: the model rows (every
// output finite, every comparison within its tolerance, and a perturbed direct computation
// caught), the baked rows with a perturbation, and the whole report (its files and document,
// every row finite, a flat field's parallax exactly 0). The command's exit codes:
// tests/bake/cli/test_report_cli.cpp.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "bake/reports/report_stability.hpp"
#include "common/diagnostics.hpp"

using namespace clothbake;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("clothbake_stability_" + std::to_string(::getpid()) + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST(StabilityReport, ModelRowsAreFiniteAndWithinTolerance) {
  reports::StabilityOptions o;
  o.baked = false;
  const auto rows = reports::stability_rows(o, scratch("model").string());
  ASSERT_GT(rows.size(), 50u);
  std::set<std::string> parameters;
  for (const auto& r : rows) {
    parameters.insert(r.parameter);
    EXPECT_EQ(r.n_nonfinite, 0u) << r.case_name << " " << r.parameter << " " << r.quantity;
    EXPECT_EQ(r.n_negative, 0u) << r.case_name << " " << r.parameter << " " << r.quantity;
    EXPECT_TRUE(r.pass) << r.case_name << " " << r.parameter << " " << r.quantity << ": "
                        << r.max_rel_error;
    EXPECT_GT(r.n_queries, 0u);
  }
  // The sweeps reach the edges the issue names.
  for (const char* p : {"roughness=0.0001", "roughness=0.001", "roughness=1", "cos_theta=1e-06",
                        "thickness=0", "thickness=inf"})
    EXPECT_TRUE(parameters.count(p)) << p;
}

TEST(StabilityReport, APerturbedDirectComputationIsCaught) {
  // Every direct computation off by 100 % (plus 100 % of its scale: more than any tolerance, which
  // are all below 1; the compressed parallax depths' reaches 0.5 of the relief, since the
  // format 1.5 steps near the pole are as coarse as the relief): every row that has a direct
  // computation and a tolerance must fail, so none of them compares a value with itself.
  reports::StabilityOptions o;
  o.perturb_direct = 1.0;
  o.table_case = false;
  const auto rows = reports::stability_rows(o, scratch("perturbed").string());
  int checked = 0;
  bool flat_parallax = false;
  for (const auto& r : rows) {
    if (r.direct.empty() || !r.tolerance || r.direct.find("(verify)") != std::string::npos)
      continue;  // verify/'s own comparisons are tested in tests/verify
    ++checked;
    EXPECT_FALSE(r.pass) << r.case_name << " " << r.parameter << " " << r.quantity;
    if (r.case_name == "flat" && r.quantity.rfind("parallax_depth", 0) == 0) flat_parallax = true;
  }
  EXPECT_GT(checked, 50);
  EXPECT_TRUE(flat_parallax);
}

TEST(StabilityReport, WritesFiniteRowsAndFlatParallaxIsExactlyZero) {
  const fs::path dir = scratch("report");
  const fs::path out = dir / "report";
  reports::StabilityOptions o;
  o.output = out.string();
  const reports::ReportOutput report = reports::stability_report(o);
  EXPECT_FALSE(report.failure) << *report.failure;
  EXPECT_NE(report.summary.find("stability report: "), std::string::npos) << report.summary;
  ASSERT_TRUE(fs::is_regular_file(out / "stability.csv"));
  ASSERT_TRUE(fs::is_regular_file(out / "stability.json"));
  EXPECT_FALSE(fs::exists(dir / "report.tmp-report"));
  std::ifstream in(out / "stability.json");
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc, report.doc);  // the file holds what --json prints
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

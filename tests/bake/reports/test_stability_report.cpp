// The stability report (bake/reports/report_stability.hpp), in process: the model rows (every
// output finite, every comparison within its tolerance, and a perturbed direct computation
// caught) and the baked rows with a perturbation. The whole report runs through the executable
// (tests/bake/cli/test_report_cli.cpp): its table case forks bakes, which must happen before the
// process has started TBB threads, as a fresh `clothbake report stability` guarantees.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
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

// `clothbake eval` end to end: the JSON answer against the library, repeats and their standard
// error, every exit code.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "eval/evaluator.hpp"
#include "tests/eval/eval_fixtures.hpp"

namespace clothbake::eval {
namespace {

using eval_test::assets;
using test_support::run_clothbake;

std::vector<std::string> query(const std::string& asset, std::vector<std::string> extra) {
  std::vector<std::string> args = {"eval", asset,         "--rect", "3.5,2.25,35.5,34.25",
                                   "--wi", "0.3,0.2,0.9", "--wo",   "-0.4,0.1,0.85"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

TEST(EvalCli, ReferenceJsonIsTheLibrarysAnswer) {
  const auto run = run_clothbake(query(assets().twill, {"--method", "reference", "--json"}));
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  for (const char* key : {"method", "spp", "value", "lobes", "std_error", "seconds_per_estimate",
                          "footprint_side_texels", "tables"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["method"], "reference");
  EXPECT_DOUBLE_EQ(j["footprint_side_texels"].get<double>(), 32.0);
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(assets().twill.c_str()).ok());
  Evaluator ev;
  ASSERT_TRUE(ev.open(asset).ok());
  const double wi[3] = {0.3, 0.2, 0.9}, wo[3] = {-0.4, 0.1, 0.85};
  Rng rng(1);
  Estimate e;
  ASSERT_TRUE(
      ev.estimate({3.5, 2.25, 35.5, 34.25}, wi, wo, Method::Reference, 1, rng, kAllLobes, &e).ok());
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(j["value"][c].get<double>(), e.value[c]);
  double sum = 0;
  for (const auto& [name, rgb] : j["lobes"].items())
    sum += rgb[1].get<double>();
  EXPECT_NEAR(sum, e.value.g, 1e-15);
  EXPECT_EQ(j["std_error"][1].get<double>(), 0.0);
}

TEST(EvalCli, RepeatsGiveAStandardErrorAndTheSeedReproduces) {
  const auto a = run_clothbake(query(assets().twill, {"--repeat", "50", "--seed", "9", "--json"}));
  const auto b = run_clothbake(query(assets().twill, {"--repeat", "50", "--seed", "9", "--json"}));
  ASSERT_EQ(a.code, 0) << a.err;
  const nlohmann::json ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
  EXPECT_EQ(ja["value"], jb["value"]);
  EXPECT_GT(ja["std_error"][1].get<double>(), 0.0);
  EXPECT_EQ(ja["method"], "multiscale");
  // One lobe only: the other parts are absent and the value is that lobe.
  const auto one = run_clothbake(
      query(assets().twill, {"--lobes", "specular_reflection", "--method", "reference", "--json"}));
  ASSERT_EQ(one.code, 0) << one.err;
  const nlohmann::json jo = nlohmann::json::parse(one.out);
  EXPECT_EQ(jo["lobes"].size(), 1u);
  EXPECT_EQ(jo["value"], jo["lobes"]["specular_reflection"]);
}

// --sheen-convention reaches the evaluator's texel BSDFs; the default is the published table.
TEST(EvalCli, SheenConventionPicksTheTable) {
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(assets().twill.c_str()).ok());
  const double wi[3] = {0.3, 0.2, 0.9}, wo[3] = {-0.999, 0.0, 0.03};
  double values[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    EvalOptions options;
    options.sheen_convention =
        k == 0 ? model::SheenConvention::Published : model::SheenConvention::Converged;
    Evaluator ev;
    ASSERT_TRUE(ev.open(asset, options).ok());
    Rng rng(1);
    Estimate e;
    ASSERT_TRUE(ev.estimate({3.5, 2.25, 35.5, 34.25}, wi, wo, Method::Reference, 1, rng,
                            lobe_bit(model::Lobe::Sheen), &e)
                    .ok());
    values[k] = e.value.g;
    std::vector<std::string> args = {"eval",    assets().twill, "--rect",   "3.5,2.25,35.5,34.25",
                                     "--wi",    "0.3,0.2,0.9",  "--wo",     "-0.999,0,0.03",
                                     "--lobes", "sheen",        "--method", "reference",
                                     "--json"};
    if (k == 1) args.insert(args.end(), {"--sheen-convention", "converged"});
    const auto run = run_clothbake(args);
    ASSERT_EQ(run.code, 0) << run.err;
    EXPECT_NEAR(nlohmann::json::parse(run.out)["value"][1].get<double>(), e.value.g,
                1e-12 * std::max(1.0, e.value.g));
  }
  EXPECT_GT(values[0], 0.0);
  EXPECT_NE(values[0], values[1]);
  const auto bad = run_clothbake(query(assets().twill, {"--sheen-convention", "exact"}));
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("--sheen-convention"), std::string::npos) << bad.err;
}

TEST(EvalCli, BadInputHasItsExitCode) {
  const std::string twill = assets().twill;
  auto code = [&](std::vector<std::string> args) {
    const auto run = run_clothbake(args);
    EXPECT_FALSE(run.err.empty());
    return run.code;
  };
  const std::vector<std::string> dirs = {"--wi", "0.3,0.2,0.9", "--wo", "-0.4,0.1,0.85"};
  auto with = [&](std::vector<std::string> head) {
    head.insert(head.end(), dirs.begin(), dirs.end());
    return head;
  };
  EXPECT_EQ(code(with({"eval", twill, "--rect", "4,0,0,4"})), 1);
  EXPECT_EQ(code(with({"eval", twill, "--rect", "0,0,4"})), 1);
  EXPECT_EQ(code(with({"eval", twill, "--rect", "0,nan,4,4"})), 1);
  EXPECT_EQ(code({"eval", twill, "--rect", "0,0,4,4", "--wi", "0,0,0", "--wo", "0,0,1"}), 1);
  EXPECT_EQ(code({"eval", twill, "--rect", "0,0,4,4", "--wi", "0,0,1", "--wo", "inf,0,1"}), 1);
  EXPECT_EQ(code(with({"eval", twill, "--rect", "0,0,4,4", "--spp", "0"})), 1);
  EXPECT_EQ(code(with({"eval", twill, "--rect", "0,0,4,4", "--lobes", "specular"})), 1);
  EXPECT_EQ(code(with({"eval", twill, "--rect", "0,0,4,4", "--method", "fast"})), 1);
  EXPECT_EQ(code(with({"eval", twill + ".missing", "--rect", "0,0,4,4"})), 2);
  EXPECT_EQ(code(with({"eval", assets().bare, "--rect", "0,0,4,4"})), 2);  // no tables
  EXPECT_EQ(code(with({"eval", assets().flat, "--rect", "0,0,4,4", "--tables", "raw"})), 2);
  // A corrupted byte: invalid asset.
  const auto bad = assets().dir / "corrupt.cbk";
  std::filesystem::copy_file(assets().flat, bad, std::filesystem::copy_options::overwrite_existing);
  {
    std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4096);
    f.put('\x5a');
  }
  EXPECT_EQ(code(with({"eval", bad.string(), "--rect", "0,0,4,4"})), 3);
}

// A footprint too small to have an area (below 1e-12 texel^2) is its corner point for every
// method: 5e-324 gave NaN and 1e-150 gave 0 for the multi-scale methods and the reference, while
// brute force and an exactly empty rectangle gave the point value.
TEST(EvalCli, TinyFootprintsGiveThePointValueForEveryMethod) {
  auto value = [&](const std::string& rect, const std::string& method) {
    const auto run = run_clothbake({"eval", assets().twill, "--rect", rect, "--wi", "0,0,1", "--wo",
                                    "0.3,0,1", "--method", method, "--json"});
    EXPECT_EQ(run.code, 0) << run.err;
    return run.code == 0 ? nlohmann::json::parse(run.out)["value"] : nlohmann::json();
  };
  const nlohmann::json point = value("0,0,0,0", "reference");
  ASSERT_TRUE(point[0].is_number()) << point;
  EXPECT_GT(point[0].get<double>(), 0.0);
  const std::pair<const char*, const char*> cases[] = {{"5e-324", "multiscale"},
                                                       {"5e-324", "reference"},
                                                       {"1e-150", "multiscale-paper"},
                                                       {"1e-150", "reference"}};
  for (const auto& [size, method] : cases)
    EXPECT_EQ(value(std::string("0,0,") + size + "," + size, method), point) << size << method;
  // Brute force on a point draws one of the view's four parallax bins per estimate (docs/
  // evaluator.md, "Brute force"): its mean is the point value, within its standard error.
  const auto brute =
      run_clothbake({"eval", assets().twill, "--rect", "0,0,1e-7,1e-7", "--wi", "0,0,1", "--wo",
                     "0.3,0,1", "--method", "brute", "--repeat", "400", "--json"});
  ASSERT_EQ(brute.code, 0) << brute.err;
  const nlohmann::json b = nlohmann::json::parse(brute.out);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(b["value"][c].get<double>(), point[c].get<double>(),
                4 * b["std_error"][c].get<double>() + 1e-12 * point[c].get<double>())
        << c;
  // A footprint of an area keeps its average (not the corner's value).
  EXPECT_NE(value("0,0,3,3", "reference"), point);
}

}  // namespace
}  // namespace clothbake::eval

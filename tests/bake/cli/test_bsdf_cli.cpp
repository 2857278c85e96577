// `clothbake bsdf`: JSON values equal the library's, the slice image holds the lobe's values on the
// documented equal-area map, and every bad argument exits with its code and a message naming the
// option, writing nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "common/image_io/image_io.hpp"
#include "model/cloth_bsdf.hpp"
#include "model/directions.hpp"
#include "tests/support/run_cli.hpp"

namespace {

namespace fs = std::filesystem;
namespace m = clothbake::model;

using clothbake::test_support::CliRun;

// Runs `clothbake bsdf ARGS` (split by the shell). Thread-safe.
CliRun run(const std::string& args) {
  return clothbake::test_support::run_clothbake_line("bsdf " + args);
}

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("clothbake_bsdf_test_" + std::to_string(::getpid()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

const std::string kParams =
    "--tangent 1,0.2,0.3 --roughness 0.3 --thickness 2 --albedo 0.7,0.6,0.5 "
    "--diffuse-reflectance 0.1 --diffuse-transmittance 0.05 --gap 0.9 ";

m::TexelParams<double> params() {
  m::TexelParams<double> p;
  p.tangent = {1, 0.2, 0.3};
  p.roughness = 0.3;
  p.optical_thickness = 2;
  p.specular_albedo = {0.7, 0.6, 0.5};
  p.diffuse_reflectance = m::Rgb<double>(0.1);
  p.diffuse_transmittance = m::Rgb<double>(0.05);
  p.gap = 0.9;
  p.sheen_color = m::Rgb<double>(0);
  return p;
}

TEST(CliBsdf, JsonMatchesTheLibrary) {
  for (const char* wo_text : {"0.1,-0.3,0.8", "-0.2,0.1,-0.7"}) {
    const CliRun r = run(kParams + "--wi 0.3,0.2,0.9 --wo " + wo_text + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const m::Vec3d wi = m::normalize(m::Vec3d{0.3, 0.2, 0.9});
    std::array<double, 3> w{};
    std::sscanf(wo_text, "%lf,%lf,%lf", &w[0], &w[1], &w[2]);
    const m::Vec3d wo = m::normalize(m::Vec3d{w[0], w[1], w[2]});
    const m::ClothBsdf<double> bsdf(params());
    const auto f = bsdf.eval(wi, wo);
    for (int l = 0; l < m::kLobeCount; ++l) {
      const auto v = f[m::Lobe(l)];
      const auto& jv = j["lobes"][m::lobe_name(m::Lobe(l))];
      EXPECT_NEAR(jv[0].get<double>(), v.r, 1e-12 * std::max(1.0, v.r)) << m::lobe_name(m::Lobe(l));
      EXPECT_NEAR(jv[2].get<double>(), v.b, 1e-12 * std::max(1.0, v.b)) << m::lobe_name(m::Lobe(l));
    }
    EXPECT_NEAR(j["total"][1].get<double>(), f.total.g, 1e-12 * std::max(1.0, f.total.g));
    EXPECT_NEAR(j["pdf"].get<double>(), bsdf.pdf(wi, wo), 1e-12 * std::max(1.0, bsdf.pdf(wi, wo)));
    EXPECT_GT(j["total"][0].get<double>(), 0.0);
  }
  // Plain-text output names every lobe.
  const CliRun text = run(kParams + "--wi 0,0,1 --wo 0,0.6,0.8");
  ASSERT_EQ(text.code, 0) << text.err;
  for (int l = 0; l < m::kLobeCount; ++l)
    EXPECT_NE(text.out.find(m::lobe_name(m::Lobe(l))), std::string::npos);
}

// --sheen-convention picks the sheen table; the default is the published one.
TEST(CliBsdf, SheenConventionPicksTheTable) {
  const std::string args = kParams + "--sheen-color 1 --sheen-roughness 0.04 " +
                           "--wi 0.7,0,0.7 --wo -0.9999,0,0.01 --json";
  m::TexelParams<double> p = params();
  p.sheen_color = m::Rgb<double>(1.0);
  p.sheen_roughness = 0.04;
  const m::Vec3d wi = m::normalize(m::Vec3d{0.7, 0, 0.7});
  const m::Vec3d wo = m::normalize(m::Vec3d{-0.9999, 0, 0.01});
  for (const char* option :
       {"", "--sheen-convention published ", "--sheen-convention converged "}) {
    const CliRun r = run(option + args);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    p.sheen_convention = std::string(option).find("converged") != std::string::npos
                             ? m::SheenConvention::Converged
                             : m::SheenConvention::Published;
    const double sheen = m::ClothBsdf<double>(p).eval(wi, wo).sheen.g;
    EXPECT_NEAR(j["lobes"]["sheen"][1].get<double>(), sheen, 1e-12 * std::max(1.0, sheen))
        << option;
  }
  p.sheen_convention = m::SheenConvention::Published;
  const double published = m::ClothBsdf<double>(p).eval(wi, wo).sheen.g;
  p.sheen_convention = m::SheenConvention::Converged;
  const double converged = m::ClothBsdf<double>(p).eval(wi, wo).sheen.g;
  EXPECT_GT(std::abs(converged - published), 0.1 * std::max(converged, published));
}

TEST(CliBsdf, SliceImageHoldsTheLobeOnTheEqualAreaMap) {
  TempDir dir;
  const fs::path exr = dir.path() / "slice.exr";
  const CliRun r =
      run(kParams + "--wi 0.3,0.2,0.9 --slice specular_reflection --resolution 32 -o " +
          exr.string() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["slice"]["hemisphere"], "upper");
  const clothbake::Image image = clothbake::read_image(exr.string());
  ASSERT_EQ(image.width, 32);
  ASSERT_EQ(image.channels, 3);
  const m::ClothBsdf<double> bsdf(params());
  const m::Vec3d wi = m::normalize(m::Vec3d{0.3, 0.2, 0.9});
  m::DirectionGrid<double> grid{32, 0.0};
  for (int y = 0; y < 32; y += 5)
    for (int x = 0; x < 32; x += 3) {
      const m::Vec3d wo = grid.direction((x + 0.5) / 32, 1 - (y + 0.5) / 32);
      const double ref = bsdf.eval(wi, wo).specular_reflection.r;
      EXPECT_NEAR(image.at(x, y, 0), ref, 1e-6 * std::max(1.0, ref)) << x << "," << y;
    }
  // Transmission lobes default to the other side; the directory holds no temporary leftovers.
  const fs::path png = dir.path() / "t.png";
  const CliRun t =
      run(kParams + "--wi 0.3,0.2,0.9 --slice diffuse_transmission --resolution 16 -o " +
          png.string() + " --json");
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_EQ(nlohmann::json::parse(t.out)["slice"]["hemisphere"], "lower");
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 2);
}

struct BadCase {
  std::string args, option;
  int code;
};

TEST(CliBsdf, BadArgumentsNameTheOption) {
  TempDir dir;
  const std::string ok_dirs = "--wi 0,0,1 --wo 0,0.6,0.8 ";
  const std::vector<BadCase> cases = {
      {"--tangent 0,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 " + ok_dirs, "--tangent", 1},
      {"--tangent 1,0 --roughness 0.3 --thickness 1 --albedo 0.5 " + ok_dirs, "--tangent", 1},
      {"--tangent 1,0,0 --roughness=-0.2 --thickness 1 --albedo 0.5 " + ok_dirs, "--roughness", 1},
      {"--tangent 1,0,0 --roughness 0 --thickness 1 --albedo 0.5 " + ok_dirs, "--roughness", 1},
      {"--tangent 1,0,0 --roughness abc --thickness 1 --albedo 0.5 " + ok_dirs, "--roughness", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness=-1 --albedo 0.5 " + ok_dirs, "--thickness", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 1.5 " + ok_dirs, "--albedo", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --gap 2 " + ok_dirs, "--gap", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --sheen-color 0.5,nan,0 " +
           ok_dirs,
       "--sheen-color", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --sheen-convention zeltner " +
           ok_dirs,
       "--sheen-convention", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,0 --wo 0,0,1", "--wi",
       1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,1 --wo inf,0,1", "--wo",
       1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,1", "--wo", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,1 --slice bogus -o " +
           (dir.path() / "x.exr").string(),
       "--slice", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,1 --slice "
       "delta_transmission -o " +
           (dir.path() / "x.exr").string(),
       "--slice", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,1 --slice sheen -o " +
           (dir.path() / "x.bmpx").string(),
       "-o", 1},
      {"--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.5 --wi 0,0,1 --slice sheen -o " +
           (dir.path() / "missing" / "x.exr").string(),
       "missing", 2},
  };
  // The executable takes about a second to start (it links every component's libraries): run the
  // cases concurrently.
  std::vector<CliRun> results(cases.size());
  {
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < cases.size(); ++k)
      threads.emplace_back([&, k] { results[k] = run(cases[k].args); });
    for (auto& t : threads)
      t.join();
  }
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const BadCase& c = cases[k];
    const CliRun& r = results[k];
    EXPECT_EQ(r.code, c.code) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.option), std::string::npos) << c.args << "\nstderr: " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.args;
  }
  // Nothing was written anywhere in the directory.
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(CliBsdf, EnergyWarningIsReported) {
  const CliRun r =
      run("--tangent 1,0,0 --roughness 0.3 --thickness 1 --albedo 0.9 --diffuse-reflectance 0.3 "
          "--wi 0,0,1 --wo 0,0.6,0.8 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_NE(r.err.find("energy"), std::string::npos);
}

}  // namespace

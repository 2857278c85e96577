// `clothbake render` end to end: outputs, JSON, bad scenes with their keys and exit codes, nothing
// written on failure.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <tuple>

#include "common/image_io/image_io.hpp"
#include "render/image_output.hpp"
#include "tests/eval/eval_fixtures.hpp"

namespace clothbake::render {
namespace {

using eval_test::assets;
using test_support::run_clothbake;
namespace fs = std::filesystem;

std::string good_scene() {
  return "[camera]\nposition = [0, 0, 2]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov_deg = 30\n"
         "resolution = [16, 12]\n[[light]]\ntype = \"point\"\nposition = [0.5, 0.5, 1.5]\n"
         "intensity = 3\n[[object]]\nshape = \"plane\"\ncenter = [0, 0, 0]\nnormal = [0, 0, 1]\n"
         "tangent = [1, 0, 0]\nsize = [2, 2]\nasset = \"" +
         assets().twill + "\"\ntiles_per_unit = 2\n";
}

fs::path write_scene(const std::string& name, const std::string& text) {
  const fs::path p = assets().dir / name;
  std::ofstream(p) << text;
  return p;
}

TEST(RenderCli, WritesTheExrAndThePreview) {
  const fs::path scene = write_scene("good.toml", good_scene());
  const fs::path out = assets().dir / "good.exr";
  const auto run = run_clothbake({"render", scene.string(), "-o", out.string(), "--json"});
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j["resolution"][0], 16);
  EXPECT_EQ(j["method"], "multiscale");
  EXPECT_GT(j["cloth_pixels"].get<int>(), 0);
  EXPECT_TRUE(fs::is_regular_file(out));
  EXPECT_TRUE(fs::is_regular_file(assets().dir / "good.png"));
  // A second run with the same seed writes the same pixels.
  const fs::path again = assets().dir / "again.exr";
  ASSERT_EQ(run_clothbake({"render", scene.string(), "-o", again.string()}).code, 0);
  std::ifstream a(out, std::ios::binary), b(again, std::ios::binary);
  const std::string sa((std::istreambuf_iterator<char>(a)), {}),
      sb((std::istreambuf_iterator<char>(b)), {});
  EXPECT_EQ(sa, sb);
}

// The PNG preview's display values in closed form: exposure in stops, the three tone maps, sRGB;
// negative and NaN radiance show black.
TEST(RenderPreview, ToneMapsInClosedForm) {
  float out[3];
  const float grey[3] = {0.25f, 0.25f, 0.25f};
  preview_value(grey, Preview{}, out);
  EXPECT_FLOAT_EQ(out[0], float(srgb_encode(0.25)));
  preview_value(grey, Preview{2.0, ToneMap::Clamp}, out);  // x 4: clipped at 1
  EXPECT_FLOAT_EQ(out[1], 1.0f);
  preview_value(grey, Preview{-1.0, ToneMap::Clamp}, out);
  EXPECT_FLOAT_EQ(out[2], float(srgb_encode(0.125)));
  // Filmic at x = 1: (2.51 + 0.03) / (2.43 + 0.59 + 0.14).
  preview_value(grey, Preview{2.0, ToneMap::Filmic}, out);
  EXPECT_NEAR(out[0], srgb_encode(2.54 / 3.16), 1e-6);
  // Reinhard on the luminance: a grey x goes to x / (1 + x); a colour keeps its channel ratios.
  preview_value(grey, Preview{2.0, ToneMap::Reinhard}, out);
  EXPECT_NEAR(out[0], srgb_encode(0.5), 1e-6);
  const float colour[3] = {0.5f, 0.25f, 0.0f};
  preview_value(colour, Preview{0.0, ToneMap::Reinhard}, out);
  const double l = 0.2126 * 0.5 + 0.7152 * 0.25;
  EXPECT_NEAR(out[0], srgb_encode(0.5 / (1 + l)), 1e-6);
  EXPECT_NEAR(out[1], srgb_encode(0.25 / (1 + l)), 1e-6);
  const float bad[3] = {-0.5f, std::nanf(""), 0.0f};
  for (ToneMap t : {ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Filmic}) {
    preview_value(bad, Preview{0.0, t}, out);
    EXPECT_EQ(out[0], 0.0f);
    EXPECT_EQ(out[1], 0.0f);
  }
}

// [render] exposure, tone_map and background: the EXR has the backdrop's radiance where the camera
// sees nothing and is linear otherwise; the PNG is the preview of the EXR's values; --exposure
// changes the PNG only.
TEST(RenderCli, PreviewFollowsTheSceneAndTheBackdropShowsWhereNothingIs) {
  std::string text = good_scene();
  text.replace(text.find("size = [2, 2]"), 13, "size = [0.3, 0.3]");
  text.replace(text.find("[[light]]"), 9,
               "[render]\nexposure = 1\ntone_map = \"filmic\"\nbackground = [0.1, 0.2, "
               "0.3]\n[[light]]");
  const fs::path scene = write_scene("preview.toml", text);
  const fs::path out = assets().dir / "preview.exr", brighter = assets().dir / "preview2.exr";
  ASSERT_EQ(run_clothbake({"render", scene.string(), "-o", out.string(), "--method", "brute"}).code,
            0);
  ASSERT_EQ(run_clothbake({"render", scene.string(), "-o", brighter.string(), "--exposure", "3",
                           "--method", "brute"})
                .code,
            0);
  const Image exr = read_image(out.string()), png = read_image(assets().dir / "preview.png");
  const Image exr2 = read_image(brighter.string()),
              png2 = read_image(assets().dir / "preview2.png");
  ASSERT_EQ(exr.width, 16);
  EXPECT_FLOAT_EQ(exr.at(0, 0, 0), 0.1f);  // a corner: the plane covers only the centre
  EXPECT_FLOAT_EQ(exr.at(0, 0, 2), 0.3f);
  EXPECT_EQ(exr.pixels, exr2.pixels);  // --exposure leaves the EXR alone
  int cloth = 0;
  for (int y = 0; y < exr.height; ++y)
    for (int x = 0; x < exr.width; ++x) {
      const float rgb[3] = {exr.at(x, y, 0), exr.at(x, y, 1), exr.at(x, y, 2)};
      float shown[3], shown2[3];
      preview_value(rgb, Preview{1.0, ToneMap::Filmic}, shown);
      preview_value(rgb, Preview{3.0, ToneMap::Filmic}, shown2);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(png.at(x, y, c), shown[c], 0.5 / 255 + 1e-6) << x << "," << y;
        EXPECT_NEAR(png2.at(x, y, c), shown2[c], 0.5 / 255 + 1e-6) << x << "," << y;
      }
      cloth += rgb[0] != 0.1f;
    }
  EXPECT_GT(cloth, 0);
  EXPECT_LT(cloth, exr.width * exr.height);
  // Through the cloth's gaps the camera sees the backdrop (the delta lobe): linear in it, with the
  // same samples (seeds) whatever its colour, so twice the backdrop adds the same again. A small
  // plain weave of thin yarns has gaps (the twill above has none).
  const fs::path gappy = assets().dir / "gappy.toml";
  std::ofstream(gappy) << "[weave]\nname = \"plain\"\n[weave.warp]\nwidth = 0.5\n[weave.weft]\n"
                          "width = 0.5\n[bake]\nresolution = 16\nparallax_dirs = 4\n"
                          "visibility_dirs = 4\nradiance_dirs = 6\nclusters = 2\n";
  text.replace(text.find("asset = \""), 9 + assets().twill.size() + 1,
               "fabric = \"" + gappy.string() + "\"");
  ASSERT_EQ(
      run_clothbake({"render", write_scene("preview-gappy.toml", text).string(), "-o", out.string(),
                     "--method", "brute", "--cache", (assets().dir / "cache-gappy").string()})
          .code,
      0);
  const Image exr_gappy = read_image(out.string());
  std::string doubled = text, black = text;
  doubled.replace(doubled.find("background = [0.1, 0.2, 0.3]"), 28, "background = [0.2, 0.4, 0.6]");
  black.replace(black.find("background = [0.1, 0.2, 0.3]"), 28, "background = [0.0, 0.0, 0.0]");
  const fs::path twice = assets().dir / "preview-twice.exr", none = assets().dir / "preview-0.exr";
  for (const auto& [name, scene_text, exr_path] : {std::tuple{"preview-twice.toml", doubled, twice},
                                                   std::tuple{"preview-0.toml", black, none}})
    ASSERT_EQ(
        run_clothbake({"render", write_scene(name, scene_text).string(), "-o", exr_path.string(),
                       "--method", "brute", "--cache", (assets().dir / "cache-gappy").string()})
            .code,
        0);
  const Image exr_twice = read_image(twice.string()), exr_none = read_image(none.string());
  double through = 0;  // the most the backdrop adds to a cloth pixel
  for (std::size_t k = 0; k < exr_gappy.pixels.size(); ++k) {
    const double once = exr_gappy.pixels[k] - exr_none.pixels[k];
    EXPECT_NEAR(exr_twice.pixels[k] - exr_none.pixels[k], 2 * once,
                1e-5 * (1 + exr_gappy.pixels[k]))
        << k;
    if (exr_none.pixels[k - k % 3] != 0.0f) through = std::max(through, once);
  }
  EXPECT_GT(through, 0.01);  // the gaps show it
}

// --image-size overrides the camera's pixels (the EXR has them) and the footprints are reported
// as sides in texels, the unit of plan and eval: halving the width at the same rows and vertical
// field of view keeps the pixel footprints; a bad size is exit 1 naming the option, before any
// work.
TEST(RenderCli, ImageSizeOverridesTheCameraAndFootprintsAreSides) {
  const fs::path scene = write_scene("sized.toml", good_scene());
  const fs::path out = assets().dir / "sized.exr";
  auto run = run_clothbake(
      {"render", scene.string(), "-o", out.string(), "--image-size", "8,12", "--json"});
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j["resolution"][0], 8);
  EXPECT_EQ(j["resolution"][1], 12);
  const auto full =
      nlohmann::json::parse(run_clothbake({"render", scene.string(), "-o",
                                           (assets().dir / "full.exr").string(), "--json"})
                                .out);
  const double side = j["footprint_side_texels"][1].get<double>(),
               full_side = full["footprint_side_texels"][1].get<double>();
  EXPECT_GT(side, 0.0);
  EXPECT_NEAR(side, full_side, 0.1 * full_side);  // the same rows: the same scale per pixel
  for (const char* bad : {"0,16", "8", "8,16,2", "8.5,16", "99999,2"}) {
    run = run_clothbake(
        {"render", scene.string(), "-o", (assets().dir / "bad.exr").string(), "--image-size", bad});
    EXPECT_EQ(run.code, 1) << bad;
    EXPECT_NE(run.err.find("--image-size"), std::string::npos) << run.err;
  }
  EXPECT_FALSE(fs::exists(assets().dir / "bad.exr"));
}

// On a terminal a render says what it bakes and shows a bar that never steps back; on a pipe, or
// with --json, stderr stays empty and stdout holds only the summary (or the JSON).
TEST(RenderCli, ProgressOnlyOnATerminal) {
  std::string scene = good_scene();
  const std::string asset_line = "asset = \"" + assets().twill + "\"";
  scene.replace(scene.find(asset_line), asset_line.size(),
                "fabric = \"" + (assets().dir / "twill.toml").string() + "\"");
  const fs::path path = write_scene("progress.toml", scene);
  const fs::path cache = assets().dir / "cache-progress";
  fs::remove_all(cache);
  const std::vector<std::string> args = {
      "render", path.string(), "-o",      (assets().dir / "progress.exr").string(),
      "--spp",  "1",           "--cache", cache.string()};
  const auto tty = test_support::run_clothbake_on_terminal(args);
  ASSERT_EQ(tty.code, 0) << tty.err;
  EXPECT_NE(tty.err.find("baking "), std::string::npos) << tty.err;
  EXPECT_NE(tty.err.find("render 16x12 multiscale 1 spp"), std::string::npos) << tty.err;
  // The percentages drawn for the render never decrease.
  int last = -1;
  bool monotone = true;
  for (std::size_t at = tty.err.find("render 16x12"); at != std::string::npos;
       at = tty.err.find("render 16x12", at + 1)) {
    const std::size_t pct = tty.err.find('%', at);
    if (pct == std::string::npos || pct < 3) break;
    const int value = std::atoi(tty.err.substr(pct - 3, 3).c_str());
    monotone = monotone && value >= last;
    last = value;
  }
  EXPECT_TRUE(monotone) << tty.err;
  EXPECT_NE(tty.out.find("rendered "), std::string::npos) << tty.out;
  fs::remove_all(cache);
  const auto pipe = run_clothbake(args);
  ASSERT_EQ(pipe.code, 0) << pipe.err;
  EXPECT_EQ(pipe.err, "");
  fs::remove_all(cache);
  auto json_args = args;
  json_args.push_back("--json");
  const auto quiet = test_support::run_clothbake_on_terminal(json_args);
  ASSERT_EQ(quiet.code, 0) << quiet.err;
  EXPECT_EQ(quiet.err.find("render 16x12"), std::string::npos) << quiet.err;
  EXPECT_EQ(quiet.err.find("baking "), std::string::npos) << quiet.err;
  EXPECT_TRUE(nlohmann::json::accept(quiet.out)) << quiet.out;
}

// -o into a missing folder creates it when the images are written; a path whose nearest existing
// ancestor is a file is refused before anything is rendered, and a failed render creates nothing.
TEST(RenderCli, OutputFoldersAreCreatedOnlyWhenWriting) {
  const fs::path scene = write_scene("folder.toml", good_scene());
  const fs::path out = assets().dir / "new" / "deeper" / "r.exr";
  fs::remove_all(assets().dir / "new");
  const auto run = run_clothbake({"render", scene.string(), "-o", out.string()});
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_TRUE(fs::is_regular_file(out));
  EXPECT_TRUE(fs::is_regular_file(fs::path(out).replace_extension(".png")));
  std::ofstream(assets().dir / "a-file") << "x";
  const auto under_file = run_clothbake(
      {"render", scene.string(), "-o", (assets().dir / "a-file" / "sub" / "r.exr").string()});
  EXPECT_EQ(under_file.code, 2) << under_file.err;
  EXPECT_NE(under_file.err.find("is not a folder"), std::string::npos) << under_file.err;
  const fs::path failing = assets().dir / "never" / "r.exr";
  const auto bad = run_clothbake(
      {"render", write_scene("bad.toml", "[camera]\n").string(), "-o", failing.string()});
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_FALSE(fs::exists(assets().dir / "never"));
}

// --sheen-convention reaches the evaluator: an explicit published equals the default, converged
// changes the cloth pixels; a bad value is a usage error.
TEST(RenderCli, SheenConventionPicksTheTable) {
  const fs::path scene = write_scene("sheen.toml", good_scene());
  auto render = [&](const std::string& name, std::vector<std::string> extra) {
    const fs::path out = assets().dir / (name + ".exr");
    std::vector<std::string> args = {"render", scene.string(), "-o", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto run = run_clothbake(args);
    EXPECT_EQ(run.code, 0) << run.err;
    std::ifstream in(out, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  const std::string by_default = render("sheen-default", {});
  EXPECT_EQ(render("sheen-published", {"--sheen-convention", "published"}), by_default);
  EXPECT_NE(render("sheen-converged", {"--sheen-convention", "converged"}), by_default);
  const auto bad =
      run_clothbake({"render", scene.string(), "-o", (assets().dir / "sheen-bad.exr").string(),
                     "--sheen-convention", "exact"});
  EXPECT_EQ(bad.code, 1);
  EXPECT_FALSE(fs::exists(assets().dir / "sheen-bad.exr"));
}

TEST(RenderCli, BadScenesNameTheKeyAndWriteNothing) {
  const std::string base = good_scene();
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = base;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  struct Case {
    std::string name, text, key;
  } cases[] = {
      {"missing-asset", replace(assets().twill, assets().twill + ".nope"), "object[0].asset"},
      {"unknown-key", replace("tiles_per_unit", "tiles_per_unti"), "tiles_per_unit"},
      {"nan-position", replace("position = [0.5, 0.5, 1.5]", "position = [0.5, nan, 1.5]"),
       "light[0].position"},
      {"zero-resolution", replace("resolution = [16, 12]", "resolution = [0, 12]"),
       "camera.resolution"},
      {"light-inside",
       replace("[[object]]\nshape = \"plane\"",
               "[[object]]\nshape = \"sphere\"\nradius = 5\n[[object]]\nshape = "
               "\"plane\""),
       "light[0].position"},
      {"no-light",
       replace("[[light]]\ntype = \"point\"\nposition = [0.5, 0.5, 1.5]\nintensity = 3\n", ""),
       "light"},
  };
  for (const Case& c : cases) {
    const fs::path scene = write_scene(c.name + ".toml", c.text);
    const fs::path out = assets().dir / (c.name + ".exr");
    const auto run = run_clothbake({"render", scene.string(), "-o", out.string()});
    EXPECT_EQ(run.code, 2) << c.name << ": " << run.err;
    EXPECT_NE(run.err.find(c.key), std::string::npos) << c.name << ": " << run.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
    EXPECT_FALSE(fs::exists(assets().dir / (c.name + ".png"))) << c.name;
  }
  // Bad options are usage errors.
  const fs::path scene = write_scene("ok.toml", base);
  EXPECT_EQ(run_clothbake(
                {"render", scene.string(), "-o", (assets().dir / "x.exr").string(), "--spp", "0"})
                .code,
            1);
  EXPECT_EQ(run_clothbake({"render", scene.string(), "-o", (assets().dir / "x.png").string()}).code,
            2);
}

}  // namespace
}  // namespace clothbake::render

namespace clothbake::render {
namespace {

// On a terminal the report says what the reference costs and shows a bar per render, numbered;
// the output folder is made only once the renders are done.
TEST(ReportErrorTime, ProgressOnATerminal) {
  const fs::path path = write_scene("tiny-tty.toml", good_scene());
  const fs::path out = assets().dir / "error-time-tty";
  fs::remove_all(out);
  const fs::path cache = assets().dir / "cache-tty";
  fs::remove_all(cache);
  const auto tty = test_support::run_clothbake_on_terminal(
      {"report", "error-time", path.string(), "-o", out.string(), "--spp", "1,2", "--methods",
       "multiscale,brute", "--cache", cache.string(), "--truth-spp", "4", "--no-plots"});
  ASSERT_EQ(tty.code, 0) << tty.err;
  EXPECT_NE(tty.err.find("rendering the reference once"), std::string::npos) << tty.err;
  EXPECT_NE(tty.err.find("--image-size W,H renders fewer"), std::string::npos) << tty.err;
  for (const char* label : {"reference 16x12", "path-traced truth 2/2, 2 spp",
                            "[1/4] multiscale 1 spp", "[4/4] brute 2 spp"})
    EXPECT_NE(tty.err.find(label), std::string::npos) << label << "\n" << tty.err;
  EXPECT_TRUE(fs::is_regular_file(out / "error-time.csv"));
}

TEST(ReportErrorTime, WritesTheCsvJsonAndPicturesOfATinyScene) {
  std::string scene = good_scene();
  scene.replace(scene.find("resolution = [16, 12]"), 21, "resolution = [64, 64]");
  const fs::path path = write_scene("tiny.toml", scene);
  const fs::path out = assets().dir / "error-time";
  const auto run = test_support::run_clothbake(
      {"report", "error-time", path.string(), "-o", out.string(), "--spp", "1,2,4,8", "--cache",
       (assets().dir / "cache").string(), "--truth-spp", "256", "--json"});
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  for (const char* f :
       {"error-time.csv", "error-time.json", "error-time.png", "error-time.svg", "grid.png"})
    EXPECT_GT(fs::file_size(out / f), 100u) << f;
  // The PNGs are images OpenImageIO reads.
  const auto info =
      test_support::detail::spawn({"/usr/bin/oiiotool", "--info", (out / "grid.png").string()});
  EXPECT_EQ(info.code, 0) << info.err;
  EXPECT_EQ(j["rows"].size(), 4u * 4u);                 // four methods (brute-path too) at four spp
  EXPECT_EQ(j["pixels_compared"].get<int>(), 64 * 64);  // the plane fills the view: no silhouette
  // Multi-scale against both brute-force baselines, in time and in samples per pixel, judged by
  // the path-traced truth first, then by the reference.
  std::vector<std::string> judges;
  for (const auto& p : j["summary"]["pairs"])
    if (p["method"] == "multiscale") {
      judges.push_back(p["judge"].get<std::string>() + " " + p["against"].get<std::string>());
      EXPECT_GT(p["equal_error_spp_ratio"].get<double>(), 0.0) << p.dump();
    }
  EXPECT_EQ(judges, (std::vector<std::string>{"truth brute", "truth brute-path", "reference brute",
                                              "reference brute-path"}));
  // The truth: brute-path converged, in two halves whose noise is measured and removed. brute-path
  // is unbiased against it, so its error is its variance, which falls as 1/spp (a ratio of 8 from
  // 1 to 8 spp; 4096 pixels give the ratio to about 10 %); the footprint reference differs from it
  // (the rectangle at the centre's directions against the pixel's true preimage) by far less than
  // brute-path's 1-spp noise.
  const nlohmann::json& truth = j["truth"];
  EXPECT_EQ(truth["spp"].get<int>(), 256);
  EXPECT_FALSE(truth["cached"].get<bool>());
  std::map<std::pair<std::string, int>, double> truth_error;
  for (const auto& row : j["rows"])
    truth_error[{row["method"].get<std::string>(), row["spp"].get<int>()}] =
        row["relmse_truth"].get<double>();
  const double path_1 = truth_error[{"brute-path", 1}], path_8 = truth_error[{"brute-path", 8}];
  EXPECT_GT(path_1 / path_8, 6.0) << path_1 << " " << path_8;
  EXPECT_LT(path_1 / path_8, 10.5) << path_1 << " " << path_8;
  const double noise = truth["noise_relmse"].get<double>();
  EXPECT_NEAR(noise, path_1 / 256, 0.3 * path_1 / 256);
  EXPECT_LT(truth["reference_relmse"].get<double>(), 0.1 * path_1);
  const double speedup = j["summary"]["equal_error_speedup"].get<double>();
  EXPECT_TRUE(std::isfinite(speedup) && speedup > 0) << speedup;
  for (const auto& row : j["rows"])
    EXPECT_GE(row["relmse"].get<double>(), 0.0);
  // The reference is cached: a second report reuses it.
  const auto again = test_support::run_clothbake(
      {"report", "error-time", path.string(), "-o", out.string(), "--spp", "1,2", "--methods",
       "multiscale,brute", "--cache", (assets().dir / "cache").string(), "--truth-spp", "256",
       "--no-plots", "--json"});
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_TRUE(nlohmann::json::parse(again.out)["reference"]["cached"].get<bool>());
  EXPECT_TRUE(nlohmann::json::parse(again.out)["truth"]["cached"].get<bool>());
  // Beyond brute-path's sweep (here 1-2 spp) its cost against the truth is extrapolated as
  // 1 / error (it is the truth's own unbiased estimator): spp = 2 relMSE(2 spp) / target.
  const auto short_sweep = test_support::run_clothbake(
      {"report", "error-time", path.string(), "-o", out.string(), "--spp", "1,2", "--methods",
       "multiscale,brute-path", "--cache", (assets().dir / "cache").string(), "--truth-spp", "256",
       "--no-plots", "--json"});
  ASSERT_EQ(short_sweep.code, 0) << short_sweep.err;
  const nlohmann::json k = nlohmann::json::parse(short_sweep.out);
  std::map<std::string, double> at_2;
  for (const auto& row : k["rows"])
    if (row["spp"] == 2) at_2[row["method"].get<std::string>()] = row["relmse_truth"].get<double>();
  ASSERT_LT(at_2["multiscale"], at_2["brute-path"]);
  int extrapolated = 0;
  for (const auto& p : k["summary"]["pairs"])
    if (p["judge"] == "truth" && p["against"] == "brute-path") {
      ++extrapolated;
      EXPECT_EQ(p["equal_error_spp_ratio_bound"], "extrapolated") << p.dump();
      EXPECT_NEAR(p["equal_error_spp_ratio"].get<double>() * 2,
                  2 * at_2["brute-path"] / at_2["multiscale"], 1e-9 * at_2["brute-path"])
          << p.dump();
    }
  EXPECT_EQ(extrapolated, 1);
}

// A scene the report refuses leaves no output folder; the cached reference is keyed on everything
// it depends on: another image size or an edited environment map renders a new reference instead
// of reusing (or refusing) the old one.
TEST(ReportErrorTime, RefusesBeforeWritingAndKeysTheReferenceOnWhatItDependsOn) {
  const fs::path cache = assets().dir / "cache-keys";
  fs::remove_all(cache);
  auto report = [&](const fs::path& scene, const fs::path& out, std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "report",    "error-time",       scene.string(), "-o",           out.string(), "--spp", "1",
        "--methods", "multiscale,brute", "--cache",      cache.string(), "--no-plots", "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_clothbake(args);
  };
  // Refused: an unknown key; --near-field without a cloth plane. Nothing is created.
  std::string bad = good_scene();
  bad.replace(bad.find("tiles_per_unit"), 14, "tiles_per_unti");
  const fs::path out_bad = assets().dir / "report-bad";
  auto run = report(write_scene("report-bad.toml", bad), out_bad, {});
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_NE(run.err.find("tiles_per_unit"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out_bad));
  std::string sphere = good_scene();
  const std::string plane = "shape = \"plane\"";
  sphere.replace(sphere.find(plane), plane.size(), "shape = \"sphere\"\nradius = 0.5");
  for (const char* key : {"normal = [0, 0, 1]\n", "tangent = [1, 0, 0]\n", "size = [2, 2]\n"})
    sphere.erase(sphere.find(key), std::string(key).size());
  run = report(write_scene("report-sphere.toml", sphere), out_bad, {"--near-field"});
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_NE(run.err.find("--near-field"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out_bad));

  // Image size: a second size is a second reference; the first is still in the cache.
  const fs::path scene = write_scene("report-keys.toml", good_scene());
  const fs::path out = assets().dir / "report-keys";
  const std::pair<const char*, bool> sizes[] = {{"8,8", false}, {"12,10", false}, {"8,8", true}};
  for (const auto& [size, expect_cached] : sizes) {
    run = report(scene, out, {"--image-size", size});
    ASSERT_EQ(run.code, 0) << size << ": " << run.err;
    EXPECT_EQ(nlohmann::json::parse(run.out)["reference"]["cached"].get<bool>(), expect_cached)
        << size;
  }
  // Environment map: the same file name with other pixels is another reference.
  const fs::path map = assets().dir / "report-keys-sky.exr";
  std::string env = good_scene();
  const std::string point = "type = \"point\"\nposition = [0.5, 0.5, 1.5]\nintensity = 3";
  env.replace(env.find(point), point.size(),
              "type = \"environment\"\nmap = \"" + map.string() + "\"");
  const fs::path env_scene = write_scene("report-keys-env.toml", env);
  bool cached[3];
  const char* colours[3] = {"0.5,0.6,0.7", "0.5,0.6,0.7", "0.9,0.6,0.7"};
  for (int k = 0; k < 3; ++k) {
    if (k != 1) {
      const auto made = test_support::detail::spawn(
          {"/usr/bin/oiiotool", "--pattern", std::string("constant:color=") + colours[k], "16x8",
           "3", "-d", "half", "-o", map.string()});
      ASSERT_EQ(made.code, 0) << made.err;
    }
    run = report(env_scene, out, {"--image-size", "8,8", "--reference-spp", "2"});
    ASSERT_EQ(run.code, 0) << run.err;
    cached[k] = nlohmann::json::parse(run.out)["reference"]["cached"].get<bool>();
  }
  EXPECT_FALSE(cached[0]);
  EXPECT_TRUE(cached[1]);   // the same map: the cached reference
  EXPECT_FALSE(cached[2]);  // new pixels: a new reference
}

// --raw-tables: the multi-scale methods with the raw and with the compressed tables of the same
// assets. The paper's form reads the tables directly, so compression changes its image a little;
// an asset without compressed tables is refused before anything is written; a `fabric =` object is
// baked with its raw tables into the cache.
TEST(ReportErrorTime, RawTablesShowWhatTheCompressionChanges) {
  const fs::path cache = assets().dir / "cache-raw";
  auto report = [&](const std::string& scene_text, const std::string& name) {
    return run_clothbake({"report", "error-time", write_scene(name + ".toml", scene_text).string(),
                          "-o", (assets().dir / name).string(), "--spp", "1,4", "--image-size",
                          "16,12", "--raw-tables", "--cache", cache.string(), "--no-plots",
                          "--json"});
  };
  auto run = report(good_scene(), "report-raw");
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json tables = nlohmann::json::parse(run.out)["tables"];
  EXPECT_EQ(tables["spp"].get<int>(), 4);
  EXPECT_FALSE(tables["methods"].contains("brute"));
  for (const char* m : {"multiscale", "multiscale-paper"}) {
    const nlohmann::json& t = tables["methods"][m];
    for (const char* k : {"relmse_compressed_vs_raw", "relmse_raw", "relmse_compressed"})
      EXPECT_TRUE(std::isfinite(t[k].get<double>()) && t[k].get<double>() >= 0) << m << k;
  }
  const double paper = tables["methods"]["multiscale-paper"]["relmse_compressed_vs_raw"];
  EXPECT_GT(paper, 0.0);   // the compressed tables are not the raw ones...
  EXPECT_LT(paper, 0.01);  // ...but close (the bake's error target)

  // The flat asset has raw tables only: refused, naming the object, no output folder.
  std::string flat = good_scene();
  flat.replace(flat.find(assets().twill), assets().twill.size(), assets().flat);
  run = report(flat, "report-raw-flat");
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_NE(run.err.find("object[0]"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(assets().dir / "report-raw-flat"));

  // A fabric: baked with --keep-raw into the cache.
  std::string fabric = good_scene();
  const std::string asset_line = "asset = \"" + assets().twill + "\"";
  fabric.replace(fabric.find(asset_line), asset_line.size(),
                 "fabric = \"" + (assets().dir / "twill.toml").string() + "\"");
  run = report(fabric, "report-raw-fabric");
  ASSERT_EQ(run.code, 0) << run.err;
  bool raw_variant = false;
  for (const auto& entry : fs::directory_iterator(cache / "assets"))
    raw_variant |= entry.path().filename().string().find("-raw.cbk") != std::string::npos;
  EXPECT_TRUE(raw_variant);
}

}  // namespace
}  // namespace clothbake::render

namespace clothbake::render {
namespace {

// `clothbake plan` on the far swatch: a distant, front-lit, fixed view of the twill. The rules
// leave out the transmission tables (no light behind), reduce the half-vector bins to a few, and
// report footprints of hundreds of texels; a missing scene is exit 2 naming it.
TEST(PlanCli, FarSwatchLeavesOutWhatTheSceneCannotSee) {
  const std::string scene = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/scenes/far-swatch.toml";
  const auto run = run_clothbake({"plan", scene, "--json"});
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  ASSERT_EQ(j["fabrics"].size(), 1u);
  const auto& f = j["fabrics"][0];
  EXPECT_GT(f["usage"]["footprint_side_texels"]["min"].get<double>(), 100.0);
  EXPECT_EQ(f["usage"]["lit_opposite_side"], 0);
  std::map<std::string, std::string> decision;
  for (const auto& d : f["decisions"])
    decision[d["item"]] = d["decision"];
  EXPECT_EQ(decision["transmission and gap tables"], "left out");
  EXPECT_EQ(decision["half-vector bins"], "reduced");
  EXPECT_LT(f["usage"]["half_vector_bins_used"].get<int>(), 64);
  EXPECT_EQ(f["usage"]["half_vector_bins_total"], 1024);
  const auto missing = run_clothbake({"plan", "/nonexistent/scene.toml"});
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("/nonexistent/scene.toml"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace clothbake::render

namespace clothbake::render {
namespace {

// good_scene() with its point light replaced by an environment light of `map`.
std::string environment_scene(const fs::path& map) {
  std::string env = good_scene();
  const std::string point = "type = \"point\"\nposition = [0.5, 0.5, 1.5]\nintensity = 3";
  env.replace(env.find(point), point.size(),
              "type = \"environment\"\nmap = \"" + map.string() + "\"");
  return env;
}

// An EXR of 16 x 8 pixels (ZIP, 16 lines a chunk) whose header declares `side` x `side`: windows
// patched and the line offset table grown to the declared chunks (all pointing at the one chunk
// of pixels), so that OpenEXR opens it as a small file of a huge image (the 33 KB file).
fs::path exr_declaring(const std::string& name, int side) {
  const fs::path map = assets().dir / name;
  const auto made = test_support::detail::spawn(
      {"/usr/bin/oiiotool", "--pattern", "constant:color=0.5,0.6,0.7", "16x8", "3", "-d", "half",
       "--compression", "zip", "-o", map.string()});
  EXPECT_EQ(made.code, 0) << made.err;
  std::ifstream in(map, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  std::size_t p = 8;  // magic and version, then attributes: name, type, int32 size, value
  while (bytes.at(p) != '\0') {
    const std::string attribute = bytes.c_str() + p;
    p += attribute.size() + 1;
    p += std::strlen(bytes.c_str() + p) + 1;
    int32_t size;
    std::memcpy(&size, bytes.data() + p, 4);
    p += 4;
    if (attribute == "dataWindow" || attribute == "displayWindow") {
      const int32_t box[4] = {0, 0, side - 1, side - 1};
      std::memcpy(bytes.data() + p, box, sizeof box);
    }
    p += std::size_t(size);
  }
  const std::size_t table = p + 1;  // one chunk: one 8-byte offset
  const uint64_t chunks = (uint64_t(side) + 15) / 16, grown = (chunks - 1) * 8;
  uint64_t first;
  std::memcpy(&first, bytes.data() + table, 8);
  first += grown;
  std::string offsets;
  for (uint64_t k = 0; k < chunks; ++k)
    offsets.append(reinterpret_cast<const char*>(&first), 8);
  bytes = bytes.substr(0, table) + offsets + bytes.substr(table + 8);
  std::ofstream(map, std::ios::binary | std::ios::trunc) << bytes;
  return map;
}

// Environment maps: sides and pixel count are checked from the header before any pixel is
// allocated (65536^2 declared in a small file was "out of memory", exit 4; 16000^2 took 3 GB and
// 10 s), and channels past the first three are ignored as documented (5 channels were refused).
TEST(RenderHardening, EnvironmentMapsAreBoundedAndExtraChannelsIgnored) {
  const fs::path five = assets().dir / "five-channels.exr";
  const auto made = test_support::detail::spawn({"/usr/bin/oiiotool", "--pattern",
                                                 "constant:color=0.5,0.6,0.7,1,0.25", "16x8", "5",
                                                 "-d", "half", "-o", five.string()});
  ASSERT_EQ(made.code, 0) << made.err;
  auto run = run_clothbake({"render", write_scene("env5.toml", environment_scene(five)).string(),
                            "-o", (assets().dir / "env5.exr").string(), "--spp", "1"});
  EXPECT_EQ(run.code, 0) << run.err;
  const std::pair<int, const char*> declared[] = {{65536, "at most 16384 pixels a side"},
                                                  {16000, "at most 33554432 are accepted"}};
  for (const auto& [side, message] : declared) {
    const fs::path map = exr_declaring("declared-" + std::to_string(side) + ".exr", side);
    const fs::path out = assets().dir / "declared.exr";
    const auto start = std::chrono::steady_clock::now();
    run = run_clothbake({"render", write_scene("declared.toml", environment_scene(map)).string(),
                         "-o", out.string()});
    EXPECT_EQ(run.code, 2) << side << ": " << run.err;
    EXPECT_NE(run.err.find("light[0].map"), std::string::npos) << run.err;
    EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
    EXPECT_LT(run.max_rss_kb, 1 << 20) << side;  // 3 GB and more before
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10);
    EXPECT_FALSE(fs::exists(out));
  }
}

// Objects naming one asset share one opened asset and evaluator: 2000 of them cost what one
// does (5000 took 2.2 GB, about 420 KB each; 15 000 ended in exit 3).
TEST(RenderHardening, ObjectsNamingOneAssetShareIt) {
  const std::string object = good_scene().substr(good_scene().find("[[object]]"));
  std::string many = good_scene();
  for (int k = 1; k < 2000; ++k)
    many += object;
  const auto one = run_clothbake({"render", write_scene("one.toml", good_scene()).string(), "-o",
                                  (assets().dir / "one.exr").string(), "--spp", "1"});
  ASSERT_EQ(one.code, 0) << one.err;
  const auto run = run_clothbake({"render", write_scene("many.toml", many).string(), "-o",
                                  (assets().dir / "many.exr").string(), "--spp", "1"});
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_LT(run.max_rss_kb, one.max_rss_kb + 100 * 1024) << one.max_rss_kb;
}

// Two different fabrics in one scene each get their own asset, the one `clothbake bake` makes: the
// scene's one stage cache memoises digests by artifact name within a run, and before it forgot
// them between runs (StageCache::begin_run) the second fabric of the same resolution got entries
// of the first.
TEST(RenderCli, EachSceneFabricIsBakedFromItsOwnToml) {
  const fs::path matrix = assets().dir / "red-matrix.toml";
  std::ofstream(matrix)
      << "name = \"red broken twill\"\n[weave]\nmatrix = [\"1100\", \"0110\", "
         "\"1001\", \"0011\"]\n[weave.warp]\nspacing_mm = 0.15\n"
         "[[yarn]]\nname = \"red-warp\"\nroughness = 0.7\ncolor = [0.8, 0.1, 0.1]\n"
         "[[yarn]]\nname = \"red-weft\"\nroughness = 0.7\ncolor = [0.7, 0.1, 0.1]\n"
         "[bake]\nresolution = 64\n";
  std::string scene = good_scene();
  const std::string asset_line = "asset = \"" + assets().twill + "\"";
  scene.replace(scene.find(asset_line), asset_line.size(),
                "fabric = \"" + (assets().dir / "twill.toml").string() + "\"");
  scene +=
      "[[object]]\nshape = \"plane\"\ncenter = [0, 0, 0.5]\nnormal = [0, 0, 1]\n"
      "tangent = [1, 0, 0]\nsize = [0.5, 0.5]\nfabric = \"" +
      matrix.string() + "\"\ntiles_per_unit = 2\n";
  const fs::path cache = assets().dir / "cache-two-fabrics";
  fs::remove_all(cache);
  const auto run = run_clothbake({"render", write_scene("two-fabrics.toml", scene).string(), "-o",
                                  (assets().dir / "two-fabrics.exr").string(), "--spp", "1",
                                  "--cache", cache.string(), "--json"});
  ASSERT_EQ(run.code, 0) << run.err;
  auto content_hash = [](const std::string& asset) {
    const auto info = run_clothbake({"info", asset, "--json"});
    EXPECT_EQ(info.code, 0) << info.err;
    return info.code == 0 ? nlohmann::json::parse(info.out)["content_hash"].get<std::string>()
                          : std::string();
  };
  // Each asset has the content of `clothbake bake` of its own TOML (without a cache).
  std::map<std::string, std::string> hash_by_stem;
  for (const auto& entry : fs::directory_iterator(cache / "assets")) {
    const std::string file = entry.path().filename().string();
    hash_by_stem[file.rfind("red-matrix-", 0) == 0 ? "red-matrix"
                                                   : file.substr(0, file.find('-'))] =
        content_hash(entry.path().string());
  }
  ASSERT_EQ(hash_by_stem.size(), 2u);
  for (const char* stem : {"twill", "red-matrix"}) {
    const fs::path alone = assets().dir / (std::string(stem) + "-alone.cbk");
    const auto bake =
        run_clothbake({"bake", (assets().dir / (std::string(stem) + ".toml")).string(), "-o",
                       alone.string(), "--no-cache"});
    ASSERT_EQ(bake.code, 0) << bake.err;
    EXPECT_EQ(hash_by_stem[stem], content_hash(alone.string())) << stem;
  }
}

// A scene's fabric goes through the refusals of `clothbake bake` before it is baked on the fly
// (a fabric that bake refuses in 0.4 s was baked anyway: 2.7 GB and 26 s, or exit 4).
TEST(RenderHardening, SceneFabricsAreRefusedUpFrontLikeBake) {
  const fs::path fabric = assets().dir / "too-large.toml";
  std::ofstream(fabric) << "[weave]\nname = \"plain\"\n[bake]\nresolution = 4096\n"
                           "radiance_dirs = 64\n";
  std::string scene = good_scene();
  const std::string asset_line = "asset = \"" + assets().twill + "\"";
  scene.replace(scene.find(asset_line), asset_line.size(), "fabric = \"" + fabric.string() + "\"");
  const fs::path cache = assets().dir / "cache-too-large";
  const auto start = std::chrono::steady_clock::now();
  const auto run =
      run_clothbake({"render", write_scene("too-large-scene.toml", scene).string(), "-o",
                     (assets().dir / "too-large.exr").string(), "--cache", cache.string()});
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_NE(run.err.find("[bake] resolution = 4096, radiance_dirs = 64 need ~"), std::string::npos)
      << run.err;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5);
  EXPECT_FALSE(fs::exists(assets().dir / "too-large.exr"));
  EXPECT_TRUE(!fs::exists(cache / "assets") || fs::is_empty(cache / "assets"));
}

// Sample counts whose renders would run for days are usage errors (4294967296 was converted into
// an int by `report error-time`: undefined behaviour, 2^31 samples).
TEST(RenderHardening, SampleCountsAndTimeBudgetsAreBounded) {
  const std::string scene = write_scene("bounded.toml", good_scene()).string();
  const std::string out = (assets().dir / "bounded.exr").string();
  const std::vector<std::vector<std::string>> refused = {
      {"render", scene, "-o", out, "--spp", "4294967296"},
      {"render", scene, "-o", out, "--spp", "1000000000"},
      {"render", scene, "-o", out, "--time-budget", "1e6"},
      {"report", "error-time", scene, "-o", out + "-report", "--spp", "4294967296"},
      {"report", "error-time", scene, "-o", out + "-report", "--spp", "1,1000000000"},
      {"report", "error-time", scene, "-o", out + "-report", "--truth-spp", "3"},
      {"report", "error-time", scene, "-o", out + "-report", "--truth-spp", "4000000000"}};
  for (const auto& args : refused) {
    const auto run = run_clothbake(args);
    EXPECT_EQ(run.code, 1) << args[4] << " " << args.back() << ": " << run.err;
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(out + "-report"));
  EXPECT_NE(run_clothbake(refused[1]).err.find("2^36"), std::string::npos);
}

// The cached reference and the cached path-traced truth are cache entries: another channel count
// (4 was heap corruption, 1 read past its end), NaN pixels (`nan` rows) or a truncated file (which
// left DIR/images/ behind the failure) are warned about and rendered again. --no-plots lists no
// picture it did not draw.
TEST(RenderHardening, CachedReferenceIsCheckedLikeACacheEntry) {
  const fs::path cache = assets().dir / "cache-reference";
  fs::remove_all(cache);
  const fs::path scene = write_scene("reference.toml", good_scene());
  const fs::path out = assets().dir / "reference-report";
  auto report = [&](bool json) {
    std::vector<std::string> args = {
        "report",       "error-time", scene.string(), "-o",    out.string(),
        "--spp",        "1",          "--methods",    "brute", "--cache",
        cache.string(), "--no-plots", "--truth-spp",  "8"};
    if (json) args.push_back("--json");
    return run_clothbake(args);
  };
  auto run = report(false);
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(run.out.find(".png"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("{error-time.csv,error-time.json}"), std::string::npos) << run.out;
  // The reference and the first half of the path-traced truth, each damaged in turn.
  for (const std::string prefix : {"reference-", "truth-"}) {
    fs::path cached;
    for (const auto& e : fs::directory_iterator(cache))
      if (e.path().extension() == ".exr" && e.path().filename().string().rfind(prefix, 0) == 0 &&
          (prefix == "reference-" || e.path().stem().string().back() == 'a'))
        cached = e.path();
    ASSERT_FALSE(cached.empty()) << prefix;
    const std::string what = prefix == "reference-" ? "reference" : "path-traced truth";
    std::ifstream in(cached, std::ios::binary);
    const std::string good((std::istreambuf_iterator<char>(in)), {});
    const auto image = [&](int w, int h, int channels, float value) {
      Image img(w, h, channels);
      for (float& v : img.pixels)
        v = value;
      write_image(cached.string(), img, PixelType::Float32);
    };
    const std::pair<const char*, std::function<void()>> damaged[] = {
        {"4 channels", [&] { image(16, 12, 4, 0.5f); }},
        {"1 channel", [&] { image(16, 12, 1, 0.5f); }},
        {"NaN", [&] { image(16, 12, 3, std::nanf("")); }},
        {"truncated", [&] {
           std::ofstream(cached, std::ios::binary | std::ios::trunc)
               << good.substr(0, good.size() / 2);
         }}};
    for (const auto& [damage_name, damage] : damaged) {
      damage();
      run = report(true);
      ASSERT_EQ(run.code, 0) << damage_name << ": " << run.err;
      EXPECT_NE(run.err.find("cached " + what + " " + cached.string() + " is unusable"),
                std::string::npos)
          << damage_name << ": " << run.err;
      const nlohmann::json j = nlohmann::json::parse(run.out);
      EXPECT_NE(j["reference"]["cached"].get<bool>(), what == "reference") << damage_name;
      EXPECT_NE(j["truth"]["cached"].get<bool>(), what != "reference") << damage_name;
      for (const auto& row : j["rows"])
        for (const char* error : {"relmse", "relmse_truth", "relmse_truth_interior"})
          EXPECT_TRUE(std::isfinite(row[error].get<double>())) << damage_name << " " << error;
    }
  }
}

}  // namespace
}  // namespace clothbake::render

// Assets the evaluator tests share, baked once per test executable through the bake library:
//   twill: the demo twill at 64^2 with raw and compressed tables (--keep-raw), its clusters split
//          by yarn and a rank-4 visibility basis (the bake's defaults)
//   flat:  a flat 16^2 fabric where every approximation of the paper is exact: constant height
//          (no parallax, V = 1), one yarn of roughness 1 (D = 1/pi: no binning error), one constant
//          tangent and colour, one cluster; a 4 x 4 checker of gaps for the delta lobe
//   bare:  the twill without Integral-Radiance tables (stages up to the clusters)
//   satin: a glossy satin5 at 64^2 (compressed tables)
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "compress/compress_settings.hpp"
#include "tests/support/run_cli.hpp"

namespace clothbake::eval_test {

inline const char* kTwillToml = R"(name = "twill 64"
[weave]
name = "twill3/1"
[weave.warp]
spacing_mm = 0.30
width = 0.92
height_mm = 0.16
twist_deg = 25
[weave.weft]
spacing_mm = 0.30
width = 0.88
height_mm = 0.14
twist_deg = 20
[[yarn]]
name = "warp"
roughness = 0.40
optical_thickness = 2.0
specular_albedo = 0.64
diffuse_reflectance = 0.24
diffuse_transmittance = 0.12
color = [0.05, 0.09, 0.26]
[[yarn]]
name = "weft"
roughness = 0.45
optical_thickness = 2.0
specular_albedo = 0.53
diffuse_reflectance = 0.30
diffuse_transmittance = 0.17
color = [0.78, 0.74, 0.64]
[sheen]
color = 0.25
roughness = 0.45
[bake]
resolution = 64
)";

// A glossy warp-faced satin (long floats, roughness 0.06 and 0.1) at 64^2 with 48^2 half-vector
// bins (the default 126^2 would only slow the bake; unbiasedness does not depend on the bins).
inline const char* kSatinToml = R"(name = "satin 64"
[weave]
name = "satin5"
[[yarn]]
name = "warp"
roughness = 0.06
color = [0.55, 0.08, 0.10]
[[yarn]]
name = "weft"
roughness = 0.10
color = [0.45, 0.40, 0.35]
[bake]
resolution = 64
radiance_dirs = 48
)";

inline const char* kFlatToml = R"(name = "flat"
[maps]
height = "flat_height.exr"
tangent = "flat_tangent.exr"
gap = "flat_gap.exr"
[[yarn]]
name = "only"
roughness = 1.0
optical_thickness = 1.5
specular_albedo = 0.5
diffuse_reflectance = 0.3
diffuse_transmittance = 0.2
color = [0.8, 0.6, 0.4]
[sheen]
color = 0.3
roughness = 0.5
[bake]
clusters = 1
)";

struct Assets {
  std::filesystem::path dir;
  std::string twill, flat, bare, satin, striped;
  ~Assets() {
    std::error_code ec;
    if (!dir.empty()) std::filesystem::remove_all(dir, ec);  // the process's own folder only
  }
};

inline void write_text(const std::filesystem::path& path, const char* text) {
  std::ofstream(path) << text;
}

inline void run_or_fail(const std::vector<std::string>& argv) {
  const test_support::CliRun run = test_support::detail::spawn(argv);
  ASSERT_EQ(run.code, 0) << argv[0] << " failed:\n" << run.out << run.err;
}

// Bakes the fabric `toml` into `out` in this process, through the bake library, as `clothbake bake
// TOML -o OUT --quiet --no-cache [--keep-raw] [--stages ...]` does: the evaluator's tests need no
// executable.
inline void bake(const std::string& toml, const std::string& out, bool keep_raw = false,
                 std::vector<std::string> stage_names = {}) {
  pipeline::BakeRequest request;
  request.fabric_path = toml;
  request.output_path = out;
  request.stages = std::move(stage_names);
  if (keep_raw) {
    compress::CompressRequest compression;
    compression.keep_raw = true;
    request.seeds.put(stages::kCompressSettingsArtifact, compression);
  }
  set_quiet(true);
  try {
    pipeline::bake(request, stages::bake_stages());
  } catch (const std::exception& e) {
    set_quiet(false);
    FAIL() << toml << ": " << e.what();
  }
  set_quiet(false);
}

// The folder the fixture assets are baked into, shared by every process of this test executable
// (the shards of one binary run side by side, docs/performance.md "The suite's time"): under the
// build folder, named after the executable and its size and modification time, so that a rebuilt
// binary bakes afresh (and removes the folders of its earlier builds).
inline std::filesystem::path shared_fixture_dir() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const std::string stem = exe.filename().string();
  const std::string key = stem + "-" + std::to_string(fs::file_size(exe, ec)) + "-" +
                          std::to_string(fs::last_write_time(exe, ec).time_since_epoch().count());
  const fs::path root = fs::path(CLOTHBAKE_BINARY_DIR) / "test-fixtures";
  const fs::path dir = root / key;
  if (!fs::exists(dir, ec))
    for (const auto& entry : fs::directory_iterator(root, ec))
      if (entry.path().filename().string().rfind(stem + "-", 0) == 0)
        fs::remove_all(entry.path(), ec);
  fs::create_directories(dir, ec);
  return dir;
}

// Writes `text` to `path` through a temporary file renamed into place (processes may race).
inline void write_text_atomically(const std::filesystem::path& path, const char* text) {
  const std::filesystem::path temp = path.string() + ".tmp" + std::to_string(::getpid());
  write_text(temp, text);
  std::filesystem::rename(temp, path);
}

// The flat fabric's three maps into `dir` (oiiotool; through temporary names).
inline void write_flat_maps(const std::filesystem::path& dir) {
  const std::string pid = std::to_string(::getpid());
  const auto make = [&](const char* name, std::vector<std::string> pattern) {
    const std::filesystem::path temp = dir / (pid + "_" + name);
    std::vector<std::string> argv = {"/usr/bin/oiiotool"};
    argv.insert(argv.end(), pattern.begin(), pattern.end());
    argv.insert(argv.end(), {"-d", "float", "-o", temp.string()});
    run_or_fail(argv);
    std::filesystem::rename(temp, dir / name);
  };
  make("flat_height.exr", {"--pattern", "constant:color=0.25", "16x16", "1"});
  make("flat_tangent.exr", {"--pattern", "constant:color=0.6,0.8,0", "16x16", "3"});
  make("flat_gap.exr", {"--pattern", "checker:width=4:height=4:color1=1:color2=0", "16x16", "1"});
}

// The twill with its four warp ends dyed three colours (one warp yarn: its clusters mix colours),
// as a weaving draft's warp colours do.
inline std::string striped_toml() {
  std::string toml = kTwillToml;
  const std::string weave = "name = \"twill3/1\"\n";
  toml.insert(toml.find(weave) + weave.size(),
              "end_colors = [[0.05, 0.09, 0.26], [0.70, 0.12, 0.10], [0.05, 0.09, 0.26], "
              "[0.85, 0.80, 0.30]]\n");
  return toml;
}

// The five assets, baked once per test executable into shared_fixture_dir() (each missing one by
// the first process that needs it: two that race bake the same bytes, and the writer renames a
// finished file into place), and a fresh temporary folder of this process (dir) with the fabric
// descriptions and maps, where the tests write their own files.
inline const Assets& assets() {
  static const Assets baked = [] {
    Assets a;
    a.dir =
        std::filesystem::temp_directory_path() / ("clothbake_eval_" + std::to_string(::getpid()));
    std::filesystem::create_directories(a.dir);
    write_text(a.dir / "twill.toml", kTwillToml);
    write_text(a.dir / "flat.toml", kFlatToml);
    write_text(a.dir / "satin.toml", kSatinToml);
    write_flat_maps(a.dir);
    const std::filesystem::path shared = shared_fixture_dir();
    const auto path = [&](const char* name) { return (shared / name).string(); };
    a.twill = path("twill.cbk");
    a.flat = path("flat.cbk");
    a.bare = path("bare.cbk");
    a.satin = path("satin.cbk");
    a.striped = path("striped.cbk");
    if (!std::filesystem::exists(a.twill) || !std::filesystem::exists(a.flat) ||
        !std::filesystem::exists(a.bare) || !std::filesystem::exists(a.satin) ||
        !std::filesystem::exists(a.striped)) {
      write_text_atomically(shared / "twill.toml", kTwillToml);
      write_text_atomically(shared / "flat.toml", kFlatToml);
      write_text_atomically(shared / "satin.toml", kSatinToml);
      write_text_atomically(shared / "striped.toml", striped_toml().c_str());
      write_flat_maps(shared);
      if (!std::filesystem::exists(a.twill)) bake(path("twill.toml"), a.twill, true);
      if (!std::filesystem::exists(a.flat)) bake(path("flat.toml"), a.flat);
      if (!std::filesystem::exists(a.satin)) bake(path("satin.toml"), a.satin);
      if (!std::filesystem::exists(a.striped)) bake(path("striped.toml"), a.striped);
      if (!std::filesystem::exists(a.bare))
        bake(path("twill.toml"), a.bare, false, {"feature_maps", "parallax", "cluster"});
    }
    return a;
  }();
  return baked;
}

}  // namespace clothbake::eval_test

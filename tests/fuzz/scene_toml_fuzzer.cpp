// libFuzzer harness of the scene loader (bake/inputs/scene_load.hpp): any bytes as a scene TOML
// must load to a scene that the renderer can take (a light and an object, finite numbers,
// environment maps within the size limit with finite radiances >= 0), or fail with
// clothbake::Error of the input kind (exit 2), never an internal error, another exception or a
// crash. The text is written to scene.toml in a scratch directory of its own that also holds
// sky.exr (the example environment map, 128 x 64), a file standing in for an asset and a fabric,
// so that relative paths to them resolve; any other path is missing or, as /dev/zero, refused.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "bake/inputs/scene_load.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "tests/fuzz/fuzz_files.hpp"

namespace {

namespace fs = std::filesystem;

const std::string& scratch_file() {
  static const std::string path = [] {
    const std::string dir = clothbake::fuzz::scratch_directory("scene");
    const fs::path sky = fs::path(__FILE__).parent_path() / "../../examples/scenes/sky.exr";
    std::error_code ec;
    fs::copy_file(sky, fs::path(dir) / "sky.exr", ec);
    if (ec) __builtin_trap();
    for (const char* name : {"asset.cbk", "fabric.toml"})
      if (std::FILE* f = std::fopen((fs::path(dir) / name).c_str(), "wb")) std::fclose(f);
    return dir + "/scene.toml";
  }();
  return path;
}

bool finite(const clothbake::render::Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace clothbake;
  set_quiet(true);
  const std::string& path = scratch_file();
  fuzz::write_file(path, data, size);
  try {
    const inputs::LoadedScene loaded = inputs::load_scene(path);
    const render::Scene& scene = loaded.scene;
    if (scene.lights.empty() || scene.objects.empty()) __builtin_trap();
    if (loaded.fabrics.size() != scene.objects.size()) __builtin_trap();
    if (!finite(scene.camera.position) || scene.camera.width < 1 || scene.camera.height < 1)
      __builtin_trap();
    for (const render::Light& l : scene.lights) {
      if (l.type != render::LightType::Environment) continue;
      const render::EnvironmentMap& env = l.environment;
      if (env.width < 1 || env.height < 1 ||
          uint64_t(env.width) * uint64_t(env.height) > inputs::kMaxEnvironmentPixels ||
          env.rgb.size() != std::size_t(env.width) * env.height * 3)
        __builtin_trap();
      for (float v : env.rgb)
        if (!(v >= 0.f) || !std::isfinite(v)) __builtin_trap();
    }
    for (const render::Object& o : scene.objects)
      if (!finite(o.center) || !(o.tiles_per_unit > 0)) __builtin_trap();
  } catch (const Error& e) {
    if (e.code() != ExitCode::Input) __builtin_trap();
  } catch (...) {
    __builtin_trap();  // anything else would reach the CLI as an internal error (exit 4)
  }
  (void)take_warnings();
  return 0;
}

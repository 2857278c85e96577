// Fabrics of a scene baked into the cache (scene_bake.hpp).
#include "bake/cli/scene_bake.hpp"

#include <cstdlib>
#include <filesystem>

#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/error.hpp"
#include "common/version.hpp"
#include "fabric/fabric_json.hpp"

namespace clothbake::cli {

namespace fs = std::filesystem;

std::string scene_cache_dir(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("CLOTHBAKE_CACHE"); env != nullptr && *env != '\0') return env;
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
    return (fs::path(home) / ".cache" / "clothbake").string();
  return (fs::temp_directory_path() / "clothbake-cache").string();
}

void bake_scene_fabrics(inputs::LoadedScene& loaded, const std::string& cache_option, bool quiet) {
  std::string cache;
  for (std::size_t k = 0; k < loaded.fabrics.size(); ++k) {
    if (loaded.fabrics[k].empty()) continue;
    if (cache.empty()) {
      cache = scene_cache_dir(cache_option);
      std::error_code ec;
      fs::create_directories(cache, ec);
      if (ec || !fs::is_directory(cache))
        throw_input_error(cache + ": cannot create the asset cache (" + ec.message() + ")");
    }
    Fabric fabric = load_fabric(loaded.fabrics[k]);
    std::string key = std::string(CLOTHBAKE_VERSION_STRING) + "\n" +
                      bake_settings_json(fabric.bake)
                          .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) +
                      "\n";
    for (const InputFile& f : fabric.inputs)
      key += f.role + " " + f.xxh64 + "\n";
    const std::string stem = fs::path(loaded.fabrics[k]).stem().string();
    const fs::path asset = fs::path(cache) / (stem + "-" + inputs::xxh64_hex(key) + ".cbk");
    std::error_code ec;
    if (!fs::is_regular_file(asset, ec)) {
      pipeline::BakeRequest request;
      request.fabric = std::move(fabric);
      request.output_path = asset.string();
      request.run.show_progress = !quiet;
      pipeline::bake(request, stages::bake_stages());
    }
    loaded.scene.objects[k].asset = asset.string();
  }
}

}  // namespace clothbake::cli

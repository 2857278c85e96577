// Fabrics of a scene baked through the stage cache (scene_bake.hpp).
#include "bake/reports/scene_bake.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bake/cache/stage_cache.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/pipeline/progress.hpp"
#include "bake/pipeline/resource_usage.hpp"
#include "bake/stages/cache_support.hpp"
#include "bake/stages/memory_estimate.hpp"
#include "bake/stages/stages.hpp"
#include "common/error.hpp"
#include "common/version.hpp"
#include "compress/compress_settings.hpp"
#include "formats/reader/layout.hpp"

namespace clothbake::reports {

namespace fs = std::filesystem;

namespace {

// XXH3-128 of everything the asset's bytes depend on (scene_bake.hpp), as 32 hex digits.
std::string asset_key(const Fabric& fabric, const cache::Codecs& codecs) {
  pipeline::Artifacts a;
  a.put("fabric", fabric);
  const cache::Codec* codec = codecs.for_artifact(a, "fabric");
  if (codec == nullptr) throw_internal_error("no cache codec for the fabric");
  cache::ByteWriter w;
  w.str("clothbake scene asset");
  w.str(CLOTHBAKE_VERSION_STRING);
  w.pod(cache::kCacheSchema);
  w.pod(uint16_t(reader::kFormatMajor));
  w.pod(uint16_t(reader::kFormatMinor));
  w.str(codec->tag);
  codec->encode(a, "fabric", w);
  const XXH128_hash_t h = XXH3_128bits(w.bytes().data(), w.bytes().size());
  char hex[33];
  std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return hex;
}

// Holds flock on `path` (created if needed) until destroyed; a no-op when it cannot be opened.
struct FileLock {
  explicit FileLock(const fs::path& path) {
    fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) return;
    while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
    }
  }
  ~FileLock() {
    if (fd >= 0) ::close(fd);
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  int fd = -1;
};

}  // namespace

std::string scene_cache_dir(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("CLOTHBAKE_CACHE"); env != nullptr && *env != '\0') return env;
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
    return (fs::path(home) / ".cache" / "clothbake").string();
  return (fs::temp_directory_path() / "clothbake-cache").string();
}

void bake_scene_fabrics(inputs::LoadedScene& loaded, const std::string& cache_option, bool quiet,
                        bool keep_raw_tables) {
  std::string cache;
  std::unique_ptr<cache::DiskCache> stage_cache;  // one for every fabric (it forgets between runs)
  const cache::Codecs codecs = stages::artifact_codecs();
  std::map<std::string, std::string> asset_of;  // fabric path -> asset: each fabric loaded once
  std::vector<std::string> chosen;  // the render's assets so far: a later bake must not prune them
  compress::CompressRequest compression;
  compression.keep_raw = keep_raw_tables;
  for (std::size_t k = 0; k < loaded.fabrics.size(); ++k) {
    if (loaded.fabrics[k].empty()) continue;
    if (const auto it = asset_of.find(loaded.fabrics[k]); it != asset_of.end()) {
      loaded.scene.objects[k].asset = it->second;
      continue;
    }
    // The refusals `clothbake bake` makes before loading anything: a fabric too large for the
    // machine fails here in milliseconds, naming its [bake] keys.
    stages::check_fabric_memory(loaded.fabrics[k], compression, {}, 0,
                                pipeline::machine_memory_bytes());
    if (cache.empty()) {
      cache = scene_cache_dir(cache_option);
      std::error_code ec;
      fs::create_directories(fs::path(cache) / cache::kAssetFolder, ec);
      if (!ec) fs::create_directories(fs::path(cache) / "locks", ec);
      if (ec || !fs::is_directory(fs::path(cache) / cache::kAssetFolder))
        throw_input_error(cache + ": cannot create the asset cache (" + ec.message() + ")");
    }
    const Fabric fabric = load_fabric(loaded.fabrics[k]);
    const std::string key = asset_key(fabric, codecs) + (keep_raw_tables ? "-raw" : "");
    const std::string stem = fs::path(loaded.fabrics[k]).stem().string();
    const fs::path asset = fs::path(cache) / cache::kAssetFolder / (stem + "-" + key + ".cbk");
    chosen.push_back(asset.string());
    if (stage_cache) stage_cache->keep_file(asset.string());
    // One process bakes a given asset; a concurrent render of the same fabric waits, then uses it.
    const FileLock lock(fs::path(cache) / "locks" / ("asset-" + key + ".lock"));
    std::error_code ec;
    if (fs::is_regular_file(asset, ec)) {
      ::utimensat(AT_FDCWD, asset.c_str(), nullptr, 0);  // most recently used
    } else {
      if (!stage_cache) {
        cache::CacheOptions options;
        options.dir = cache;
        stage_cache = std::make_unique<cache::DiskCache>(options, codecs);
        for (const std::string& kept : chosen)  // this one included
          stage_cache->keep_file(kept);
      }
      // From the path, as `clothbake bake f.toml` does (the asset's metadata lists load_fabric
      // among the stages), so that the asset has the bytes of that command's.
      // On a terminal the bake says what it is doing (a scene's first render can bake for
      // minutes); on a pipe it stays silent unless something goes wrong.
      const bool show = !quiet && pipeline::ProgressBar::stderr_is_terminal();
      if (show)
        std::fprintf(stderr, "baking %s for the scene (not in the asset cache %s yet)\n",
                     terminal_safe(loaded.fabrics[k]).c_str(), terminal_safe(cache).c_str());
      pipeline::BakeRequest request;
      request.fabric_path = loaded.fabrics[k];
      request.output_path = asset.string();
      request.run.show_progress = show;
      request.run.cache = stage_cache->enabled() ? stage_cache.get() : nullptr;
      if (keep_raw_tables) request.seeds.put(stages::kCompressSettingsArtifact, compression);
      pipeline::bake(request, stages::bake_stages());
      stage_cache->enforce_bound();  // the asset counts towards the bound as well
    }
    loaded.scene.objects[k].asset = asset.string();
    asset_of[loaded.fabrics[k]] = asset.string();
  }
}

}  // namespace clothbake::reports

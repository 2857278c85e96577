// The content-keyed cache of finished stage outputs (docs/batch.md, "Cache"): a folder of entry
// files, one per (stage, key), written atomically (temporary file, fsync, rename), checksummed,
// least recently used out beyond a size bound. Safe for concurrent bakes sharing the folder: a
// per-key lock file makes one process compute a stage while the others wait and then read its
// entry; a killed process leaves at most a temporary file, never a torn entry.
//
// Key of a stage = XXH3-128 of: the cache schema, the tool version, the asset format version, the
// stage name, and for every input (declared or collected, sorted by name) its name and digest.
// The digest of an output of a keyed stage is XXH3-128(stage key, output name), so a key never
// needs the values upstream; the digest of any other artifact (seeds, outputs of uncached stages
// such as load_fabric's fabric) is the XXH3-128 of its codec encoding. A stage's key_view
// replaces inputs by stand-ins (their content is hashed instead).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bake/cache/codec.hpp"
#include "bake/pipeline/stage.hpp"

namespace clothbake::cache {

inline constexpr uint64_t kDefaultCacheMaxBytes = uint64_t(10) << 30;  // 10 GiB
inline constexpr uint32_t kCacheSchema = 4;  // bump when the entry layout or a codec changes
// Largest index an entry may declare (its outputs' names, tags, offsets and checksums: a few
// hundred bytes in practice); checked before anything is read or allocated for it.
inline constexpr uint64_t kMaxEntryIndexBytes = uint64_t(1) << 20;
// Subfolder of finished assets that scene renders keep beside the entries
// (bake/reports/scene_bake): counted by cache_info as stage "asset" and bounded with the entries
// (least recently used out).
inline constexpr const char* kAssetFolder = "assets";

struct CacheOptions {
  std::string dir;
  uint64_t max_bytes = kDefaultCacheMaxBytes;  // least recently used entries out beyond this
};

// `option` when non-empty, else $CLOTHBAKE_CACHE, else "" (no cache).
std::string cache_dir_from(const std::string& option);

// Parses "500M", "10G", "1.5GiB", "123456" (bytes; K/M/G/T are powers of 1024). Error(Usage)
// naming `option` for anything else.
uint64_t parse_size(const std::string& text, const std::string& option);

// hits, misses and unstored describe the current pipeline run (since the last begin_run): when a
// corrupt entry makes the driver run again, they describe the attempt that produced the result,
// so hits + misses + unstored is the number of cacheable stages that ran. corrupt counts every
// entry removed since the DiskCache was made, the aborted attempts' included.
struct CacheCounts {
  int hits = 0;
  int misses = 0;    // ran and stored
  int corrupt = 0;   // entries that failed their checksum or decoding (removed, recomputed)
  int unstored = 0;  // ran, could not be stored (no codec, cache not writable)
};

// Memoises the digests of artifacts by name within a pipeline run and forgets them when the next
// run begins (begin_run), so one DiskCache may serve several bakes (the fabrics of a scene); any
// number may share one folder.
class DiskCache final : public pipeline::StageCache {
 public:
  // Creates the folder if needed. A folder that cannot be created or written is warned about
  // once (naming it) and the cache is off: the bake runs uncached rather than failing.
  DiskCache(CacheOptions options, Codecs codecs);
  ~DiskCache() override;
  DiskCache(const DiskCache&) = delete;
  DiskCache& operator=(const DiskCache&) = delete;

  bool enabled() const { return enabled_; }
  bool load(const pipeline::Stage& stage, const pipeline::Artifacts& available,
            pipeline::Artifacts& produced) override;
  bool store(const pipeline::Stage& stage, const pipeline::Artifacts& available,
             const pipeline::Artifacts& produced) override;
  bool discard_hits(const std::string& why) override;
  void begin_run() override;
  const CacheCounts& counts() const { return *counts_; }
  // Keys of the stages seen in the current run (stage name -> 32 hex digits); the last one of a
  // bake (the compress stage's, or any stage's) identifies the bake's computed content.
  const std::map<std::string, std::string>& keys() const { return keys_; }
  // Prunes the folder to the bound when it holds more (done after each store; a caller that adds
  // files of its own, such as the assets of scene renders, calls it after adding them).
  void enforce_bound();
  // A file of the folder (a path; only its name is compared, as prune_cache does) that the bound
  // never removes while this cache lives: the assets a scene render has already chosen, which a
  // later fabric's bake of the same render must not prune before the render opens them.
  void keep_file(const std::string& path);

 private:
  struct Key {
    uint64_t high = 0, low = 0;
    std::string hex() const;
  };
  std::optional<Key> content_digest(const pipeline::Artifacts& a, const std::string& name) const;
  std::optional<Key> digest(const pipeline::Artifacts& available, const std::string& name);
  std::optional<Key> stage_key(const pipeline::Stage& stage, const pipeline::Artifacts& available);
  std::string entry_path(const std::string& stage, const Key& key) const;
  bool read_entry(const std::string& path, const pipeline::Stage& stage, const Key& key,
                  pipeline::Artifacts& out);
  void publish(const pipeline::Stage& stage, const Key& key);
  void release(const std::string& stage);

  CacheOptions options_;
  Codecs codecs_;
  bool enabled_ = false;
  bool warned_store_ = false;
  std::shared_ptr<CacheCounts> counts_ = std::make_shared<CacheCounts>();
  std::map<std::string, Key> derived_;                  // outputs of keyed stages
  std::map<std::string, std::optional<Key>> content_;   // memoised content digests
  std::map<std::string, std::pair<Key, int>> pending_;  // stage -> key, lock fd
  std::map<std::string, std::string> keys_;
  std::set<std::string> hit_paths_;   // entries answered from since the last discard_hits
  std::set<std::string> kept_files_;  // keep_file: names the bound never removes
};

struct CacheInfo {
  uint64_t entries = 0;
  uint64_t bytes = 0;
  uint64_t temporary_files = 0;                                    // left by killed stores
  std::map<std::string, std::pair<uint64_t, uint64_t>> per_stage;  // stage -> entries, bytes
};                                                                 // ("asset": kAssetFolder)
// What the folder holds. Error(Input) if it is not a readable folder.
CacheInfo cache_info(const std::string& dir);

struct PruneResult {
  uint64_t removed_entries = 0, removed_bytes = 0, kept_entries = 0, kept_bytes = 0;
};
// Removes least recently used entries and assets (oldest mtime first; a hit refreshes the mtime)
// until the rest fit in `max_bytes` (0: remove all), and temporary files older than an hour.
// Files named in `in_use` (file names, not paths: the entries a running bake was answered from)
// are never removed; they still count towards the bound.
PruneResult prune_cache(const std::string& dir, uint64_t max_bytes,
                        const std::set<std::string>& in_use = {});

}  // namespace clothbake::cache

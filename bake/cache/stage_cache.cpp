#include "bake/cache/stage_cache.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "common/diagnostics.hpp"
#include "common/version.hpp"
#include "formats/reader/layout.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::cache {
namespace fs = std::filesystem;
namespace {

constexpr char kMagic[8] = {'C', 'B', 'K', 'C', 'A', 'C', 'H', 'E'};

struct Hasher {
  Hasher() {
    state = XXH3_createState();
    XXH3_128bits_reset(state);
  }
  ~Hasher() { XXH3_freeState(state); }
  void bytes(const void* p, std::size_t n) { XXH3_128bits_update(state, p, n); }
  void str(const std::string& s) {
    const uint64_t n = s.size();
    bytes(&n, sizeof n);
    bytes(s.data(), s.size());
  }
  XXH128_hash_t finish() const { return XXH3_128bits_digest(state); }
  XXH3_state_t* state;
};

std::string errno_text() {
  return std::strerror(errno);
}

}  // namespace

std::string DiskCache::Key::hex() const {
  char buf[33];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(high),
                static_cast<unsigned long long>(low));
  return buf;
}

std::string cache_dir_from(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("CLOTHBAKE_CACHE"); env && *env) return env;
  return "";
}

uint64_t parse_size(const std::string& text, const std::string& option) {
  // DIGITS[.DIGITS][UNIT]: UNIT one of K, M, G, T (any case), optionally followed by "i", then an
  // optional "B"; or a bare "B". A fraction needs a unit (a byte count is whole). Nothing else:
  // no sign, spaces, exponent or hexadecimal.
  auto refuse = [&]() -> uint64_t {
    throw Error(ExitCode::Usage,
                option + " expects a size such as 500M, 10G or 123456 (bytes), got '" + text + "'");
  };
  std::size_t at = 0;
  auto digits = [&] {
    const std::size_t start = at;
    while (at < text.size() && text[at] >= '0' && text[at] <= '9')
      ++at;
    return at - start;
  };
  if (digits() == 0) return refuse();
  bool fraction = false;
  if (at < text.size() && text[at] == '.') {
    ++at;
    if (digits() == 0) return refuse();
    fraction = true;
  }
  const double value = std::stod(text.substr(0, at));
  std::string unit = text.substr(at);
  if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
  if (unit.size() == 2 && unit[1] == 'i') unit.pop_back();
  double scale = 0;
  if (unit.empty())
    scale = 1;
  else if (unit == "K" || unit == "k")
    scale = 1024.0;
  else if (unit == "M" || unit == "m")
    scale = 1024.0 * 1024;
  else if (unit == "G" || unit == "g")
    scale = 1024.0 * 1024 * 1024;
  else if (unit == "T" || unit == "t")
    scale = 1024.0 * 1024 * 1024 * 1024;
  if (scale == 0 || (fraction && scale == 1) || value * scale > 1.8e19) return refuse();
  return uint64_t(value * scale);
}

DiskCache::DiskCache(CacheOptions options, Codecs codecs)
    : options_(std::move(options)), codecs_(std::move(codecs)) {
  std::error_code ec;
  fs::create_directories(fs::path(options_.dir) / "entries", ec);
  if (!ec) fs::create_directories(fs::path(options_.dir) / "locks", ec);
  const std::string entries = (fs::path(options_.dir) / "entries").string();
  if (ec) {
    warn("cache " + options_.dir + " cannot be created (" + ec.message() +
         "): baking without the cache");
  } else if (::access(entries.c_str(), W_OK | X_OK) != 0) {
    warn("cache " + options_.dir + " is not writable (" + errno_text() +
         "): baking without the cache");
  } else {
    enabled_ = true;
  }
}

DiskCache::~DiskCache() {
  for (auto& [stage, pending] : pending_)
    ::close(pending.second);  // closing drops the flock
}

std::optional<DiskCache::Key> DiskCache::content_digest(const pipeline::Artifacts& a,
                                                        const std::string& name) const {
  const Codec* codec = codecs_.for_artifact(a, name);
  if (codec == nullptr) return std::nullopt;
  Hasher h;
  h.str(codec->tag);
  ByteWriter w(h.state);  // streams the encoding into the hash
  codec->encode(a, name, w);
  const XXH128_hash_t d = h.finish();
  return Key{d.high64, d.low64};
}

std::optional<DiskCache::Key> DiskCache::digest(const pipeline::Artifacts& available,
                                                const std::string& name) {
  if (auto it = derived_.find(name); it != derived_.end()) return it->second;
  if (auto it = content_.find(name); it != content_.end()) return it->second;
  return content_[name] = content_digest(available, name);
}

std::optional<DiskCache::Key> DiskCache::stage_key(const pipeline::Stage& stage,
                                                   const pipeline::Artifacts& available) {
  std::vector<std::string> names = stage.inputs;
  for (const auto& prefix : stage.collects)
    for (const auto& n : available.names(prefix))
      names.push_back(n);
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  pipeline::Artifacts view;
  if (stage.key_view) stage.key_view(available, view);

  Hasher h;
  h.str("clothbake stage cache");
  h.bytes(&kCacheSchema, sizeof kCacheSchema);
  h.str(CLOTHBAKE_VERSION_STRING);
  const uint16_t format[2] = {reader::kFormatMajor, reader::kFormatMinor};
  h.bytes(format, sizeof format);
  h.str(stage.name);
  for (const auto& n : names) {
    if (!available.contains(n)) continue;  // an optional input that no stage produced
    const std::optional<Key> d = view.contains(n) ? content_digest(view, n) : digest(available, n);
    if (!d) return std::nullopt;
    h.str(n);
    h.bytes(&d->high, 8);
    h.bytes(&d->low, 8);
  }
  const XXH128_hash_t d = h.finish();
  return Key{d.high64, d.low64};
}

std::string DiskCache::entry_path(const std::string& stage, const Key& key) const {
  return (fs::path(options_.dir) / "entries" / (stage + "-" + key.hex() + ".entry")).string();
}

void DiskCache::publish(const pipeline::Stage& stage, const Key& key) {
  keys_[stage.name] = key.hex();
  for (const auto& out : stage.outputs) {
    Hasher h;
    h.bytes(&key.high, 8);
    h.bytes(&key.low, 8);
    h.str(out);
    const XXH128_hash_t d = h.finish();
    derived_[out] = Key{d.high64, d.low64};
  }
}

void DiskCache::release(const std::string& stage) {
  if (auto it = pending_.find(stage); it != pending_.end()) {
    ::close(it->second.second);
    pending_.erase(it);
  }
}

// Entry layout (docs/batch.md, "Cache entries"): a 32-byte header (magic "CBKCACHE", u32 schema,
// u32 output count, key as u64 high, u64 low), the payloads one after the other, an index (per
// output: str name, str codec tag, u64 offset, u64 size, u64 XXH3-64 of the payload) and a 24-byte
// trailer (u64 index offset, u64 index size, u64 XXH3-64 of header and index). Opening an entry
// checks the header, index and trailer; a payload is read and checked when a stage reads it.
bool DiskCache::read_entry(const std::string& path, const pipeline::Stage& stage, const Key& key,
                           pipeline::Artifacts& out) {
  // Non-blocking: a FIFO in place of an entry must not stop the bake (it is refused below).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0 && errno == ENOENT) return false;
  std::string problem;
  try {
    if (fd < 0) throw_input_error("cannot open it: " + errno_text());
    struct stat st {};
    if (::fstat(fd, &st) != 0) throw_input_error(errno_text());
    if (!S_ISREG(st.st_mode)) throw_input_error("not a regular file");
    const uint64_t size = uint64_t(st.st_size);
    auto read_at = [&](uint64_t offset, uint64_t n) {
      if (offset > size || n > size - offset) throw_input_error("truncated");
      std::vector<std::byte> b(static_cast<std::size_t>(n));
      std::size_t got = 0;
      while (got < n) {
        const ssize_t r = ::pread(fd, b.data() + got, n - got, off_t(offset + got));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) throw_input_error("truncated");
        got += std::size_t(r);
      }
      return b;
    };
    if (size < 32 + 24) throw_input_error("shorter than its header");
    const std::vector<std::byte> trailer = read_at(size - 24, 24);
    ByteReader t(trailer.data(), trailer.size());
    const uint64_t index_offset = t.pod<uint64_t>(), index_size = t.pod<uint64_t>();
    const uint64_t sum = t.pod<uint64_t>();
    if (index_offset < 32 || index_offset > size - 24 || index_size != size - 24 - index_offset)
      throw_input_error("bad trailer");
    // The declared size is checked before anything is allocated for it.
    if (index_size > kMaxEntryIndexBytes)
      throw_input_error("an index of " + std::to_string(index_size) + " bytes (at most " +
                        std::to_string(kMaxEntryIndexBytes) + ")");
    const std::vector<std::byte> head = read_at(0, 32);
    const std::vector<std::byte> index = read_at(index_offset, index_size);
    XXH3_state_t* state = XXH3_createState();
    XXH3_64bits_reset(state);
    XXH3_64bits_update(state, head.data(), head.size());
    XXH3_64bits_update(state, index.data(), index.size());
    const uint64_t computed = XXH3_64bits_digest(state);
    XXH3_freeState(state);
    if (computed != sum) throw_input_error("checksum mismatch");
    ByteReader r(head.data(), 32);
    char magic[8];
    for (char& c : magic)
      c = char(r.pod<uint8_t>());
    if (std::memcmp(magic, kMagic, 8) != 0) throw_input_error("not a cache entry");
    if (r.pod<uint32_t>() != kCacheSchema) throw_input_error("other schema");
    const uint32_t count = r.pod<uint32_t>();
    const uint64_t high = r.pod<uint64_t>(), low = r.pod<uint64_t>();
    if (high != key.high || low != key.low) throw_input_error("holds another key");
    pipeline::Artifacts values;
    ByteReader ir(index.data(), index.size());
    for (uint32_t k = 0; k < count; ++k) {
      const std::string name = ir.str();
      const std::string tag = ir.str();
      const uint64_t offset = ir.pod<uint64_t>(), bytes = ir.pod<uint64_t>();
      const uint64_t hash = ir.pod<uint64_t>();
      const Codec* codec = codecs_.for_tag(tag);
      if (codec == nullptr) throw_input_error("unknown codec '" + tag + "'");
      if (offset < 32 || offset > index_offset || bytes > index_offset - offset)
        throw_input_error("'" + name + "' lies outside the payloads");
      const Codec copy = *codec;
      auto counts = counts_;
      values.put_deferred(name, *codec->type, [=](pipeline::Artifacts& into) {
        std::string why;
        try {
          const int f = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
          if (f < 0) throw_input_error("it was removed");
          struct stat fst {};
          if (::fstat(f, &fst) != 0 || !S_ISREG(fst.st_mode) ||
              uint64_t(fst.st_size) < offset + bytes) {
            ::close(f);
            throw_input_error("'" + name + "' is truncated");
          }
          // Mapped, not copied: the payload is read once by the checksum; the decoder may lend
          // large parts of it to the value (the mapping lives as long as the value needs it).
          const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
          const uint64_t start = offset / page * page, length = offset + bytes - start;
          void* map = length ? ::mmap(nullptr, length, PROT_READ, MAP_PRIVATE | MAP_POPULATE, f,
                                      off_t(start))
                             : nullptr;
          ::close(f);
          if (map == MAP_FAILED) throw_input_error("cannot map '" + name + "': " + errno_text());
          const std::shared_ptr<const void> mapping(map, [length](void* p) {
            if (p) ::munmap(p, length);
          });
          const std::byte* payload =
              map ? static_cast<const std::byte*>(map) + (offset - start) : nullptr;
          if (XXH3_64bits(payload, bytes) != hash)
            throw_input_error("'" + name + "' fails its checksum");
          ByteReader pr(payload, bytes, mapping);
          copy.decode(pr, into, name);
          if (!pr.done()) throw_input_error("'" + name + "' has trailing bytes");
          return;
        } catch (const std::exception& e) {
          why = e.what();
        }
        ++counts->corrupt;
        std::error_code ec;
        fs::remove(path, ec);
        warn("cache entry " + path + " is corrupt (" + why + "): removed, recomputing");
        throw pipeline::CacheEntryCorrupt("cache entry " + path + " is corrupt (" + why + ")");
      });
    }
    if (!ir.done()) throw_input_error("index has trailing bytes");
    for (const auto& o : stage.outputs)
      if (!values.contains(o)) throw_input_error("output '" + o + "' is missing");
    for (const auto& o : stage.outputs)
      out.take(values, o);
    ::close(fd);
    return true;
  } catch (const std::exception& e) {
    problem = e.what();
  }
  ::close(fd);
  ++counts_->corrupt;
  warn("cache entry " + path + " is corrupt (" + problem + "): removed, recomputing the " +
       stage.name + " stage");
  std::error_code ec;
  fs::remove(path, ec);
  return false;
}

bool DiskCache::load(const pipeline::Stage& stage, const pipeline::Artifacts& available,
                     pipeline::Artifacts& produced) {
  release(stage.name);  // a lock left by an attempt that failed (run_pipeline retries)
  if (!stage.cacheable) return false;
  const std::optional<Key> key = stage_key(stage, available);
  if (!key) return false;
  keys_[stage.name] = key->hex();
  if (!enabled_) return false;
  const std::string path = entry_path(stage.name, *key);
  pipeline::Artifacts values;
  bool hit = read_entry(path, stage, *key, values);
  if (!hit) {
    // Wait for a concurrent bake computing the same key, then look again.
    const std::string lock = (fs::path(options_.dir) / "locks" / (key->hex() + ".lock")).string();
    const int fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd >= 0) {
      int rc;
      do {
        rc = ::flock(fd, LOCK_EX);
      } while (rc != 0 && errno == EINTR);
      hit = read_entry(path, stage, *key, values);
      if (hit)
        ::close(fd);
      else
        pending_[stage.name] = {*key, fd};
    } else {
      pending_[stage.name] = {*key, -1};
    }
  }
  if (!hit) return false;
  produced.merge(values);
  ::utimensat(AT_FDCWD, path.c_str(), nullptr, 0);  // most recently used
  publish(stage, *key);
  ++counts_->hits;
  hit_paths_.insert(path);
  return true;
}

void DiskCache::begin_run() {
  // A new run, or a retry after a corrupt entry: count only what this run does (CacheCounts).
  counts_->hits = counts_->misses = counts_->unstored = 0;
  derived_.clear();
  content_.clear();
  keys_.clear();
  hit_paths_.clear();
}

bool DiskCache::discard_hits(const std::string& why) {
  const bool any = !hit_paths_.empty();
  for (const std::string& path : hit_paths_) {
    std::error_code ec;
    fs::remove(path, ec);
    ++counts_->corrupt;
    warn("cache entry " + path + " is corrupt (its values fail a check: " + why +
         "): removed, recomputing");
  }
  hit_paths_.clear();
  return any;
}

bool DiskCache::store(const pipeline::Stage& stage, const pipeline::Artifacts& available,
                      const pipeline::Artifacts& produced) {
  (void)available;
  auto it = pending_.find(stage.name);
  if (it == pending_.end()) {
    if (stage.cacheable) ++counts_->unstored;
    return false;
  }
  const Key key = it->second.first;
  // Outputs of a keyed stage get derived digests whether or not they can be stored.
  publish(stage, key);
  std::vector<const Codec*> codecs;
  for (const auto& o : stage.outputs) {
    codecs.push_back(codecs_.for_artifact(produced, o));
    if (codecs.back() == nullptr) {  // a type without a codec: run uncached
      release(stage.name);
      ++counts_->unstored;
      return false;
    }
  }
  bool stored = true;
  try {
    formats::OutputOptions out;
    out.require_asset_to_replace = false;
    formats::write_file_atomically(
        entry_path(stage.name, key),
        [&](formats::Sink& sink) {
          ByteWriter head;
          for (char c : kMagic)
            head.pod(uint8_t(c));
          head.pod(kCacheSchema);
          head.pod(uint32_t(stage.outputs.size()));
          head.pod(key.high);
          head.pod(key.low);
          sink.write(head.bytes().data(), head.bytes().size());
          uint64_t offset = head.bytes().size();
          ByteWriter index;
          static const std::byte zeros[64] = {};
          for (std::size_t k = 0; k < stage.outputs.size(); ++k) {
            ByteWriter payload;  // one output in memory at a time
            codecs[k]->encode(produced, stage.outputs[k], payload);
            const auto& b = payload.bytes();
            // Payloads start at multiples of 64 (a mapped payload keeps its alignment).
            const uint64_t pad = (64 - offset % 64) % 64;
            sink.write(zeros, std::size_t(pad));
            offset += pad;
            sink.write(b.data(), b.size());
            index.str(stage.outputs[k]);
            index.str(codecs[k]->tag);
            index.pod(offset);
            index.pod(uint64_t(b.size()));
            index.pod(uint64_t(XXH3_64bits(b.data(), b.size())));
            offset += b.size();
          }
          sink.write(index.bytes().data(), index.bytes().size());
          std::vector<std::byte> summed = head.bytes();
          summed.insert(summed.end(), index.bytes().begin(), index.bytes().end());
          ByteWriter trailer;
          trailer.pod(offset);
          trailer.pod(uint64_t(index.bytes().size()));
          trailer.pod(uint64_t(XXH3_64bits(summed.data(), summed.size())));
          sink.write(trailer.bytes().data(), trailer.bytes().size());
        },
        out);
  } catch (const Error& e) {
    stored = false;
    if (!warned_store_)
      warn(std::string("cache: ") + e.what() + " (the bake goes on; the entry is not kept)");
    warned_store_ = true;
  }
  release(stage.name);
  if (!stored) {
    ++counts_->unstored;
    return false;
  }
  ++counts_->misses;
  enforce_bound();
  return true;
}

void DiskCache::enforce_bound() {
  try {
    const CacheInfo info = cache_info(options_.dir);
    if (info.bytes <= options_.max_bytes) return;
    // The entries this run was answered from stay: their payloads may not have been read yet (a
    // later stage reads them), and removing one would be reported as a corrupt entry.
    std::set<std::string> in_use = kept_files_;
    for (const std::string& path : hit_paths_)
      in_use.insert(fs::path(path).filename().string());
    prune_cache(options_.dir, options_.max_bytes, in_use);
  } catch (const Error&) {
  }
}

void DiskCache::keep_file(const std::string& path) {
  kept_files_.insert(fs::path(path).filename().string());
}

namespace {
struct EntryFile {
  fs::path path;
  uint64_t bytes;
  int64_t mtime_ns;
  std::string stage;
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The entries (entries/<stage>-<key>.entry) and the scene renders' assets (assets/*.cbk); files
// starting with '.' are temporary files of stores or bakes in progress (or killed).
std::vector<EntryFile> list_entries(const std::string& dir, std::vector<EntryFile>* temporary) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw_input_error("cache " + dir + " is not a folder");
  std::vector<EntryFile> out;
  for (const char* sub : {"entries", kAssetFolder}) {
    const fs::path folder = fs::path(dir) / sub;
    const bool assets = std::string(sub) == kAssetFolder;
    if (!fs::is_directory(folder, ec)) continue;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
      struct stat st {};
      if (::stat(it->path().c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
      const std::string name = it->path().filename().string();
      EntryFile e{it->path(), uint64_t(st.st_size),
                  int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec,
                  assets ? "asset" : name.substr(0, name.rfind('-'))};
      if (name[0] == '.') {
        if (temporary) temporary->push_back(e);
      } else if (ends_with(name, assets ? ".cbk" : ".entry")) {
        out.push_back(e);
      }
    }
    if (ec) throw_input_error("cannot list cache " + folder.string() + ": " + ec.message());
  }
  return out;
}
}  // namespace

CacheInfo cache_info(const std::string& dir) {
  std::vector<EntryFile> temporary;
  CacheInfo info;
  for (const auto& e : list_entries(dir, &temporary)) {
    ++info.entries;
    info.bytes += e.bytes;
    info.per_stage[e.stage].first += 1;
    info.per_stage[e.stage].second += e.bytes;
  }
  info.temporary_files = temporary.size();
  return info;
}

PruneResult prune_cache(const std::string& dir, uint64_t max_bytes,
                        const std::set<std::string>& in_use) {
  std::vector<EntryFile> temporary;
  std::vector<EntryFile> entries = list_entries(dir, &temporary);
  std::sort(entries.begin(), entries.end(), [](const EntryFile& a, const EntryFile& b) {
    return a.mtime_ns != b.mtime_ns ? a.mtime_ns < b.mtime_ns : a.path < b.path;
  });
  uint64_t total = 0;
  for (const auto& e : entries)
    total += e.bytes;
  PruneResult result;
  std::error_code ec;
  for (const auto& e : entries) {
    if ((total > max_bytes || max_bytes == 0) && !in_use.count(e.path.filename().string())) {
      if (fs::remove(e.path, ec)) {
        ++result.removed_entries;
        result.removed_bytes += e.bytes;
        total -= e.bytes;
        continue;
      }
    }
    ++result.kept_entries;
    result.kept_bytes += e.bytes;
  }
  const int64_t hour_ago = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count() -
                           int64_t(3600) * 1000000000;
  // Only unlocked ones: a live store or bake holds its temporary's flock however long it takes.
  for (const auto& t : temporary)
    if (t.mtime_ns < hour_ago) formats::remove_if_unlocked(t.path);
  return result;
}

}  // namespace clothbake::cache

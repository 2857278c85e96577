// libFuzzer harness of the stage cache's entries (bake/cache/stage_cache.hpp, codec.hpp and the
// codecs of bake/cache/basic_codecs.cpp and bake/stages/cache_support.cpp): any bytes as an entry
// must be a miss, or a hit whose outputs each decode to a value or fail with clothbake::Error of
// the input kind (a corrupt entry: warned about, removed, recomputed), never an internal error,
// another exception, a crash or an allocation beyond the entry's own size.
//
// The first byte picks the form: even, the remaining bytes are the whole entry file (header,
// index and trailer parsing); odd, they are a list of outputs (one byte: which output and whether
// its codec tag is the right one; two bytes: the payload's length; the payload) that the harness
// lays out as an entry with correct checksums, as an adversary who recomputes them would: this is
// what reaches the decoders. The stage has one output of every codec's type.
#include <unistd.h>
#include <xxhash.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bake/cache/stage_cache.hpp"
#include "bake/stages/cache_support.hpp"
#include "bake/stages/table_streaming.hpp"
#include "cluster/visibility_clusters.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "fabric/fabric.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/asg.hpp"
#include "tests/fuzz/fuzz_files.hpp"

namespace {

using namespace clothbake;
namespace fs = std::filesystem;

struct Output {
  const char* name;
  const char* tag;
  void (*read)(const pipeline::Artifacts&, const std::string&);
};

template <class T>
void read_as(const pipeline::Artifacts& a, const std::string& name) {
  (void)a.get<T>(name);
}

const Output kOutputs[] = {
    {"section/fuzz", "sections/2", read_as<std::vector<formats::Section>>},
    {"metadata/fuzz", "json/cbor", read_as<nlohmann::json>},
    {"supersedes/fuzz", "strings", read_as<std::vector<std::string>>},
    {"name", "string", read_as<std::string>},
    {"fabric/fuzz", "fabric/1", read_as<Fabric>},
    {"asgs", "asg_params/1", read_as<std::vector<model::AsgParams<float>>>},
    {"clusters", "visibility_clusters/1", read_as<cluster::VisibilityClusters>},
    {"tables/streamed", "streamed_tables/1", read_as<stages::StreamedTablesArtifact>},
    {"compress_options", "compress_request/1", read_as<compress::CompressRequest>},
};
constexpr std::size_t kOutputCount = sizeof kOutputs / sizeof kOutputs[0];

struct Fixture {
  std::string dir;
  pipeline::Stage stage;
  pipeline::Artifacts available;
  std::unique_ptr<cache::DiskCache> cache;
  std::string entry;  // the stage's entry file
  uint64_t key_high = 0, key_low = 0;
};

Fixture& fixture() {
  static Fixture f = [] {
    Fixture out;
    out.dir = fuzz::scratch_directory("cache");
    out.stage.name = "fuzz";
    out.stage.inputs = {"x"};
    for (const Output& o : kOutputs)
      out.stage.outputs.push_back(o.name);
    out.available.put("x", std::string("fuzz input"));
    out.cache = std::make_unique<cache::DiskCache>(cache::CacheOptions{out.dir, uint64_t(1) << 30},
                                                   stages::artifact_codecs());
    pipeline::Artifacts produced;
    if (out.cache->load(out.stage, out.available, produced)) __builtin_trap();  // empty: a miss
    const std::string hex = out.cache->keys().at("fuzz");
    out.key_high = std::stoull(hex.substr(0, 16), nullptr, 16);
    out.key_low = std::stoull(hex.substr(16), nullptr, 16);
    out.entry = (fs::path(out.dir) / "entries" / ("fuzz-" + hex + ".entry")).string();
    return out;
  }();
  return f;
}

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
void put_str(std::string& out, const std::string& s) {
  put(out, uint64_t(s.size()));
  out += s;
}

// An entry with correct checksums around the outputs that `data` describes.
std::string crafted_entry(const Fixture& f, const uint8_t* data, size_t size) {
  std::string payloads, index;
  uint32_t count = 0;
  for (size_t i = 0; i + 3 <= size;) {
    const uint8_t pick = data[i];
    const size_t length = std::min<size_t>(size - i - 3, data[i + 1] | (size_t(data[i + 2]) << 8));
    i += 3;
    const Output& o = kOutputs[(pick & 0x7f) % kOutputCount];
    const char* tag = (pick & 0x80) ? kOutputs[(pick >> 4) % kOutputCount].tag : o.tag;
    payloads.append((64 - (32 + payloads.size()) % 64) % 64, '\0');
    const uint64_t offset = 32 + payloads.size();
    payloads.append(reinterpret_cast<const char*>(data + i), length);
    put_str(index, o.name);
    put_str(index, tag);
    put(index, offset);
    put(index, uint64_t(length));
    put(index, XXH3_64bits(data + i, length));
    ++count;
    i += length;
  }
  std::string entry = "CBKCACHE";
  put(entry, cache::kCacheSchema);
  put(entry, count);
  put(entry, f.key_high);
  put(entry, f.key_low);
  const std::string header = entry;
  entry += payloads;
  const uint64_t index_offset = entry.size();
  entry += index;
  put(entry, index_offset);
  put(entry, uint64_t(index.size()));
  put(entry, XXH3_64bits((header + index).data(), header.size() + index.size()));
  return entry;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  set_quiet(true);
  Fixture& f = fixture();
  if (size == 0) return 0;
  const std::string entry = (data[0] & 1)
                                ? crafted_entry(f, data + 1, size - 1)
                                : std::string(reinterpret_cast<const char*>(data + 1), size - 1);
  fuzz::write_file(f.entry, reinterpret_cast<const uint8_t*>(entry.data()), entry.size());
  try {
    pipeline::Artifacts produced;
    if (f.cache->load(f.stage, f.available, produced))
      for (const Output& o : kOutputs) {
        try {
          o.read(produced, o.name);
        } catch (const Error& e) {
          if (e.code() != ExitCode::Input) __builtin_trap();  // a corrupt entry, not a bug
        }
      }
  } catch (...) {
    __builtin_trap();  // load() itself must take any entry as a hit or a miss
  }
  (void)f.cache->discard_hits("fuzz");
  (void)take_warnings();
  return 0;
}

// The content-keyed stage cache (bake/cache/stage_cache.hpp, docs/batch.md "Cache") in process, on
// synthetic stages that pipeline::run_pipeline drives as a bake drives the real ones: a stored
// stage is a hit with the same bytes; the key follows the inputs' contents and names, the stage
// name and the declared inputs (and only a key view's stand-in); a damaged entry is never a hit
// with wrong bytes; an output type without a codec runs uncached; the size bound takes the least
// recently used entry out; prune_cache, parse_size, cache_dir_from; an unusable folder.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "bake/cache/codec.hpp"
#include "bake/cache/stage_cache.hpp"
#include "bake/pipeline/driver.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "tests/support/files.hpp"

namespace {

using namespace clothbake;
using namespace clothbake::cache;
using namespace std::chrono_literals;
namespace fs = std::filesystem;
using pipeline::Artifacts;
using pipeline::RunResult;
using pipeline::Stage;
using pipeline::StageContext;

// What the "shout" stage makes of `text`: the text, every byte value (NUL and bytes above 127, so
// that "the same bytes" covers more than printable text) and the text reversed.
std::string shouted(const std::string& text) {
  std::string out = text;
  for (int b = 0; b < 256; ++b)
    out.push_back(char(b));
  out.append(text.rbegin(), text.rend());
  return out;
}

// Cacheable: "text" -> "shout" (a std::string: the basic "string" codec). Counts its runs.
Stage shout_stage(std::shared_ptr<int> runs, const std::string& name = "shout") {
  Stage s;
  s.name = name;
  s.inputs = {"text"};
  s.outputs = {"shout"};
  s.run = [runs](StageContext& ctx) {
    ++*runs;
    ctx.output("shout", shouted(ctx.input<std::string>("text")));
  };
  return s;
}

// Cacheable, downstream of shout: "shout" -> "size".
Stage measure_stage() {
  Stage s;
  s.name = "measure";
  s.inputs = {"shout"};
  s.outputs = {"size"};
  s.run = [](StageContext& ctx) {
    ctx.output("size", std::to_string(ctx.input<std::string>("shout").size()));
  };
  return s;
}

// Not cacheable (like the write stage): "shout" -> "result". A cached output is decoded, and its
// payload checked, only when a stage reads it: this one does, inside the run.
Stage sink_stage() {
  Stage s;
  s.name = "sink";
  s.inputs = {"shout"};
  s.outputs = {"result"};
  s.cacheable = false;
  s.run = [](StageContext& ctx) { ctx.output("result", ctx.input<std::string>("shout")); };
  return s;
}

// A value type that no codec serialises.
struct Opaque {
  std::string text;
};

Codecs basic_codecs() {
  Codecs codecs;
  add_basic_codecs(codecs);
  return codecs;
}

Artifacts with_text(const std::string& text) {
  Artifacts a;
  a.put("text", text);
  return a;
}

using clothbake::test_support::slurp;

void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

// The cache state ("hit", "miss", "uncached") that a run reports for `stage`.
std::string state_of(const RunResult& r, const std::string& stage) {
  for (const auto& s : r.stages)
    if (s.name == stage) return s.cache;
  ADD_FAILURE() << "no stage " << stage;
  return "";
}

bool any_mentions(const std::vector<std::string>& messages, const std::string& text) {
  for (const auto& m : messages)
    if (m.find(text) != std::string::npos) return true;
  return false;
}

class DiskCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake-stage-cache-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cache_dir_ = (dir_ / "cache").string();
    was_quiet_ = is_quiet();
    set_quiet(true);  // the warnings are recorded and checked with take_warnings()
    take_warnings();
  }
  void TearDown() override {
    take_warnings();
    set_quiet(was_quiet_);
    fs::remove_all(dir_);
  }

  std::unique_ptr<DiskCache> open(uint64_t max_bytes = kDefaultCacheMaxBytes,
                                  const std::string& dir = "") const {
    CacheOptions options;
    options.dir = dir.empty() ? cache_dir_ : dir;
    options.max_bytes = max_bytes;
    return std::make_unique<DiskCache>(options, basic_codecs());
  }

  // Runs `stages` from `seeds` through `cache` on one thread, as a bake does.
  static RunResult run(DiskCache& cache, Artifacts seeds, const std::vector<Stage>& stages) {
    pipeline::RunOptions options;
    options.threads = 1;
    options.cache = &cache;
    return pipeline::run_pipeline({}, std::move(seeds), options, stages);
  }

  // A fresh run of `cache` (digests memoised by artifact name forgotten) that only loads `stage`:
  // its key and whether it was a hit.
  static std::pair<std::string, bool> lookup(DiskCache& cache, const Stage& stage,
                                             const Artifacts& available) {
    cache.begin_run();
    Artifacts produced;
    const bool hit = cache.load(stage, available, produced);
    const auto it = cache.keys().find(stage.name);
    return {it == cache.keys().end() ? "" : it->second, hit};
  }

  // The entry file of `stage` under the key it has in `cache`'s current run.
  fs::path entry(const DiskCache& cache, const std::string& stage) const {
    return fs::path(cache_dir_) / "entries" / (stage + "-" + cache.keys().at(stage) + ".entry");
  }
  std::vector<std::string> entry_names() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(fs::path(cache_dir_) / "entries"))
      if (e.path().extension() == ".entry") out.push_back(e.path().filename().string());
    return out;
  }

  fs::path dir_;
  std::string cache_dir_;
  bool was_quiet_ = false;
  std::shared_ptr<int> runs_ = std::make_shared<int>(0);  // runs of the shout stage
};

// The point of the cache: a second bake over the same inputs reads the stage's outputs back instead
// of running it, and they are the very bytes the stage produced. A fresh DiskCache on the folder
// stands for the next bake (nothing is kept in memory between the two).
TEST_F(DiskCacheTest, StoredStageIsAHitWithTheSameBytes) {
  const std::vector<Stage> stages = {shout_stage(runs_), sink_stage()};
  std::map<std::string, std::string> first_keys;
  {
    auto cache = open();
    ASSERT_TRUE(cache->enabled());
    const RunResult r = run(*cache, with_text("hello"), stages);
    EXPECT_EQ(state_of(r, "shout"), "miss");
    EXPECT_EQ(state_of(r, "sink"), "uncached");
    EXPECT_EQ(r.artifacts.get<std::string>("result"), shouted("hello"));
    EXPECT_EQ(cache->counts().misses, 1);
    EXPECT_EQ(cache->counts().hits, 0);
    EXPECT_EQ(cache->counts().corrupt, 0);
    EXPECT_EQ(cache->counts().unstored, 0);
    EXPECT_TRUE(fs::is_regular_file(entry(*cache, "shout")));
    first_keys = cache->keys();
  }
  EXPECT_EQ(*runs_, 1);

  auto cache = open();
  const RunResult r = run(*cache, with_text("hello"), stages);
  EXPECT_EQ(state_of(r, "shout"), "hit");
  EXPECT_EQ(*runs_, 1);  // not run again
  EXPECT_EQ(cache->counts().hits, 1);
  EXPECT_EQ(cache->counts().misses, 0);
  EXPECT_EQ(cache->counts().corrupt, 0);
  const std::string& result = r.artifacts.get<std::string>("result");
  EXPECT_EQ(result.size(), shouted("hello").size());
  EXPECT_EQ(result, shouted("hello"));  // byte for byte, NULs and high bytes included
  EXPECT_EQ(cache->keys(), first_keys);
  EXPECT_EQ(entry_names().size(), 1u);
  EXPECT_TRUE(take_warnings().empty());
}

// The StageCache contract used directly: load is false and leaves `produced` empty on a miss;
// store after that miss keeps the outputs (true), a store with no load before it keeps nothing
// (false, counted unstored); the next cache loads every output.
TEST_F(DiskCacheTest, LoadAndStoreFollowTheStageCacheContract) {
  const Stage shout = shout_stage(runs_);
  const Artifacts available = with_text("direct");
  {
    auto cache = open();
    Artifacts produced;
    EXPECT_FALSE(cache->load(shout, available, produced));
    EXPECT_TRUE(produced.names().empty());
    produced.put("shout", shouted("direct"));
    EXPECT_TRUE(cache->store(shout, available, produced));
    EXPECT_FALSE(cache->store(shout, available, produced));
    EXPECT_EQ(cache->counts().misses, 1);
    EXPECT_EQ(cache->counts().unstored, 1);
  }
  auto cache = open();
  Artifacts produced;
  ASSERT_TRUE(cache->load(shout, available, produced));
  EXPECT_EQ(produced.names(), std::vector<std::string>{"shout"});
  EXPECT_EQ(produced.get<std::string>("shout"), shouted("direct"));
  EXPECT_EQ(cache->counts().hits, 1);
}

// The key must change with everything that can change the outputs (else a stale entry is a hit
// with wrong values) and with nothing else (else the cache never hits): the content and the name of
// each declared or collected input and the stage name are in it; an artifact the stage neither
// declares nor collects is not. Each changed key is a miss while the base key stays a hit.
TEST_F(DiskCacheTest, KeyFollowsInputsStageNameAndDeclaredInputs) {
  auto cache = open();
  const Stage shout = shout_stage(runs_);
  auto seeds = [](const std::string& text, const std::string& other) {
    Artifacts a = with_text(text);
    a.put("other", other);
    return a;
  };
  const Artifacts base = seeds("hello", "x");

  const auto [k0, hit0] = lookup(*cache, shout, base);
  ASSERT_EQ(k0.size(), 32u);  // 32 hex digits
  EXPECT_FALSE(hit0);
  Artifacts produced;
  produced.put("shout", shouted("hello"));
  ASSERT_TRUE(cache->store(shout, base, produced));
  EXPECT_EQ(lookup(*cache, shout, base), std::make_pair(k0, true));

  // An input's content.
  const auto edited = lookup(*cache, shout, seeds("hellp", "x"));
  EXPECT_NE(edited.first, k0);
  EXPECT_FALSE(edited.second);
  // The stage name.
  const auto renamed_stage = lookup(*cache, shout_stage(runs_, "shout2"), base);
  EXPECT_NE(renamed_stage.first, k0);
  EXPECT_FALSE(renamed_stage.second);
  // A declared input more, then that input's content.
  Stage wider = shout;
  wider.inputs = {"text", "other"};
  const auto wide = lookup(*cache, wider, base);
  EXPECT_NE(wide.first, k0);
  EXPECT_FALSE(wide.second);
  EXPECT_NE(lookup(*cache, wider, seeds("hello", "y")).first, wide.first);
  // The same content under another input name.
  Stage renamed_input = shout;
  renamed_input.inputs = {"words"};
  Artifacts words;
  words.put("words", std::string("hello"));
  EXPECT_NE(lookup(*cache, renamed_input, words).first, k0);
  // Collected artifacts are inputs too.
  Stage collecting = shout;
  collecting.collects = {"extra/"};
  Artifacts extra = seeds("hello", "x");
  extra.put("extra/a", std::string("1"));
  Artifacts extra_edited = seeds("hello", "x");
  extra_edited.put("extra/a", std::string("2"));
  const std::string k_collect = lookup(*cache, collecting, base).first;
  const std::string k_extra = lookup(*cache, collecting, extra).first;
  EXPECT_NE(k_extra, k_collect);
  EXPECT_NE(lookup(*cache, collecting, extra_edited).first, k_extra);
  // An artifact the stage does not read is not in its key: still the stored entry.
  EXPECT_EQ(lookup(*cache, shout, seeds("hello", "y")), std::make_pair(k0, true));

  // Downstream: measure reads shout's output, whose digest derives from shout's key, so a change
  // of shout's input reaches measure's key without measure's input being hashed.
  auto chain = open();
  const std::vector<Stage> stages = {shout_stage(runs_), measure_stage()};
  run(*chain, with_text("hello"), stages);
  const std::string m_hello = chain->keys().at("measure");
  run(*chain, with_text("hello!"), stages);
  EXPECT_NE(chain->keys().at("measure"), m_hello);
  const RunResult again = run(*chain, with_text("hello"), stages);
  EXPECT_EQ(chain->keys().at("measure"), m_hello);
  EXPECT_EQ(state_of(again, "measure"), "hit");
}

// A key view (Stage::key_view) keys a stage on a stand-in holding only the part of an input it
// reads: a change outside that part (the colour) keeps the key, so the entry is a hit; a change
// inside it (the roughness) is a miss. The same stage without the view misses on the colour (the
// control: the view, not chance, keeps the colour out).
TEST_F(DiskCacheTest, KeyViewKeepsExcludedChangesOutOfTheKey) {
  auto runs = std::make_shared<int>(0);
  auto tables = [runs](bool with_view) {
    Stage s;
    s.name = "tables";
    s.inputs = {"fabric"};
    s.outputs = {"table"};
    s.run = [runs](StageContext& ctx) {
      ++*runs;
      const double r = ctx.input<nlohmann::json>("fabric")["roughness"];
      ctx.output("table", nlohmann::json{{"twice_roughness", 2 * r}});
    };
    if (with_view)
      s.key_view = [](const Artifacts& available, Artifacts& view) {
        const auto& fabric = available.get<nlohmann::json>("fabric");
        view.put("fabric", nlohmann::json{{"roughness", fabric["roughness"]}});
      };
    return s;
  };
  auto fabric = [](double roughness, const std::string& color) {
    Artifacts a;
    a.put("fabric", nlohmann::json{{"roughness", roughness}, {"color", color}});
    return a;
  };

  auto cache = open();
  const std::vector<Stage> viewed = {tables(true)};
  const RunResult red = run(*cache, fabric(0.5, "red"), viewed);
  EXPECT_EQ(state_of(red, "tables"), "miss");
  const std::string k_red = cache->keys().at("tables");
  const RunResult blue = run(*cache, fabric(0.5, "blue"), viewed);
  EXPECT_EQ(state_of(blue, "tables"), "hit");
  EXPECT_EQ(cache->keys().at("tables"), k_red);
  EXPECT_EQ(blue.artifacts.get<nlohmann::json>("table")["twice_roughness"], 1.0);
  EXPECT_EQ(*runs, 1);
  const RunResult rough = run(*cache, fabric(0.7, "red"), viewed);
  EXPECT_EQ(state_of(rough, "tables"), "miss");
  EXPECT_NE(cache->keys().at("tables"), k_red);
  EXPECT_EQ(*runs, 2);

  EXPECT_NE(lookup(*cache, tables(false), fabric(0.5, "red")).first,
            lookup(*cache, tables(false), fabric(0.5, "blue")).first);
}

// Damage to an entry on disk, wherever it lies, is found: at open (header, index, trailer, size,
// another key's entry in its place) or when a stage reads the payload (run_pipeline then runs
// again). Either way the entry is counted corrupt, removed with a warning naming it, the stage is
// recomputed and stored again (the same bytes as before: stages are deterministic), and the run
// gives the right value.
TEST_F(DiskCacheTest, DamagedEntryIsDetectedRemovedAndRecomputed) {
  const std::vector<Stage> stages = {shout_stage(runs_), sink_stage()};
  fs::path path;
  std::string other_key_bytes;
  {
    auto cache = open();
    run(*cache, with_text("world"), stages);
    other_key_bytes = slurp(entry(*cache, "shout"));
    run(*cache, with_text("hello"), stages);
    path = entry(*cache, "shout");
  }
  const std::string clean = slurp(path);
  ASSERT_GT(clean.size(), 64u + 24u);
  uint64_t index_offset = 0;
  std::memcpy(&index_offset, clean.data() + clean.size() - 24, 8);
  ASSERT_GT(index_offset, 64u);
  ASSERT_LT(index_offset, clean.size() - 24);

  auto flip = [](std::size_t at) {
    return [at](std::string b) {
      b[at] = char(b[at] ^ 0x40);
      return b;
    };
  };
  auto cut = [](std::size_t size) { return [size](std::string b) { return b.substr(0, size); }; };
  struct Case {
    std::string what;
    std::function<std::string(std::string)> damage;
  };
  const std::vector<Case> cases = {
      {"magic", flip(0)},
      {"schema", flip(8)},
      {"key in the header", flip(20)},
      {"payload length", flip(64)},
      {"payload byte", flip(64 + 8 + 3)},
      {"index", flip(std::size_t(index_offset) + 3)},
      {"trailer index offset", flip(clean.size() - 24)},
      {"trailer checksum", flip(clean.size() - 1)},
      {"truncated by one byte", cut(clean.size() - 1)},
      {"truncated to half", cut(clean.size() / 2)},
      {"truncated inside the header", cut(20)},
      {"empty", cut(0)},
      {"a byte appended", [](std::string b) { return b + 'x'; }},
      {"another key's entry", [&](std::string) { return other_key_bytes; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    spit(path, c.damage(clean));
    take_warnings();
    const int runs_before = *runs_;
    auto cache = open();
    const RunResult r = run(*cache, with_text("hello"), stages);
    EXPECT_EQ(r.artifacts.get<std::string>("result"), shouted("hello"));
    EXPECT_EQ(state_of(r, "shout"), "miss");
    EXPECT_EQ(*runs_, runs_before + 1);
    EXPECT_EQ(cache->counts().corrupt, 1);
    // The counts describe the run that produced the result: one miss, no hit, whether the entry
    // was found bad at open or when its payload was read (after the aborted attempt's hit).
    EXPECT_EQ(cache->counts().misses, 1);
    EXPECT_EQ(cache->counts().hits, 0);
    EXPECT_EQ(slurp(path), clean);  // recomputed and stored again
    const auto warnings = take_warnings();
    EXPECT_TRUE(any_mentions(warnings, "cache entry " + path.string() + " is corrupt"))
        << (warnings.empty() ? "no warning" : warnings.front());
  }
}

// Whatever single byte of an entry is flipped, a load never yields wrong bytes: the damage is found
// (counted corrupt, the entry removed) at open or when the payload is read, except in the zero
// padding between the 32-byte header and the payload (at 64), which nothing reads.
TEST_F(DiskCacheTest, EveryFlippedByteIsDetectedOrHarmless) {
  const Stage shout = shout_stage(runs_);
  const Artifacts available = with_text("hello");
  fs::path path;
  {
    auto cache = open();
    run(*cache, with_text("hello"), {shout});
    path = entry(*cache, "shout");
  }
  const std::string clean = slurp(path);
  for (std::size_t i = 0; i < clean.size(); ++i) {
    std::string damaged = clean;
    damaged[i] = char(damaged[i] ^ 0x01);
    spit(path, damaged);
    auto cache = open();
    Artifacts produced;
    if (cache->load(shout, available, produced)) {
      try {
        EXPECT_EQ(produced.get<std::string>("shout"), shouted("hello")) << "byte " << i;
      } catch (const pipeline::CacheEntryCorrupt&) {
      }
    }
    const bool detected = cache->counts().corrupt == 1;
    if (detected) {
      EXPECT_FALSE(fs::exists(path)) << "byte " << i;
    }
    if (i < 32 || i >= 64) {
      EXPECT_TRUE(detected) << "byte " << i << " of " << clean.size();
    }
  }
  take_warnings();
}

// An output whose type has no codec cannot be kept: the stage runs (reported "uncached", counted
// unstored), nothing is written for it, and the bake goes on. Its outputs still get digests derived
// from its key, so the stage reading them is cached (a hit in the next bake). An input of a type
// without a codec leaves a stage without a key: it runs uncached too.
TEST_F(DiskCacheTest, OutputWithoutCodecRunsUncachedAndTheBakeSucceeds) {
  auto opaque_runs = std::make_shared<int>(0);
  Stage opaque;
  opaque.name = "opaque";
  opaque.inputs = {"text"};
  opaque.outputs = {"opaque"};
  opaque.run = [opaque_runs](StageContext& ctx) {
    ++*opaque_runs;
    ctx.output("opaque", Opaque{ctx.input<std::string>("text")});
  };
  Stage use;
  use.name = "use";
  use.inputs = {"opaque"};
  use.outputs = {"used"};
  use.run = [](StageContext& ctx) { ctx.output("used", ctx.input<Opaque>("opaque").text + "!"); };
  const std::vector<Stage> stages = {opaque, use};
  {
    auto cache = open();
    const RunResult r = run(*cache, with_text("hello"), stages);
    EXPECT_EQ(r.artifacts.get<std::string>("used"), "hello!");
    EXPECT_EQ(state_of(r, "opaque"), "uncached");
    EXPECT_EQ(state_of(r, "use"), "miss");
    EXPECT_EQ(cache->counts().unstored, 1);
    EXPECT_EQ(cache->counts().misses, 1);
    const auto names = entry_names();
    ASSERT_EQ(names.size(), 1u);
    EXPECT_EQ(names[0].rfind("use-", 0), 0u) << names[0];
  }
  auto cache = open();
  const RunResult r = run(*cache, with_text("hello"), stages);
  EXPECT_EQ(state_of(r, "opaque"), "uncached");
  EXPECT_EQ(state_of(r, "use"), "hit");
  EXPECT_EQ(r.artifacts.get<std::string>("used"), "hello!");
  EXPECT_EQ(*opaque_runs, 2);

  Stage from_seed;
  from_seed.name = "from_seed";
  from_seed.inputs = {"blob"};
  from_seed.outputs = {"copied"};
  from_seed.run = [](StageContext& ctx) { ctx.output("copied", ctx.input<Opaque>("blob").text); };
  Artifacts seeds;
  seeds.put("blob", Opaque{"seeded"});
  auto seeded_cache = open();
  const RunResult s = run(*seeded_cache, std::move(seeds), {from_seed});
  EXPECT_EQ(s.artifacts.get<std::string>("copied"), "seeded");
  EXPECT_EQ(state_of(s, "from_seed"), "uncached");
  EXPECT_EQ(seeded_cache->counts().unstored, 1);
  EXPECT_EQ(seeded_cache->keys().count("from_seed"), 0u);
}

// --cache-max-size: after each store the folder (cache_info) holds at most max_bytes, the entries
// out being the least recently used. A hit refreshes its entry: the oldest entry, once hit,
// outlives a younger one that was not. (Recency is set with explicit mtimes: stores within one
// clock tick may share an mtime.)
TEST_F(DiskCacheTest, SizeBoundTakesTheLeastRecentlyUsedOut) {
  const std::vector<Stage> stages = {shout_stage(runs_)};
  auto text = [](char c) { return std::string(2000, c); };  // entries of one size
  uint64_t entry_bytes = 0;
  {
    const std::string probe_dir = (dir_ / "probe").string();
    auto probe = open(kDefaultCacheMaxBytes, probe_dir);
    run(*probe, with_text(text('p')), {shout_stage(std::make_shared<int>(0))});
    entry_bytes = cache_info(probe_dir).bytes;
    ASSERT_GT(entry_bytes, 4000u);
  }
  const uint64_t max_bytes = 3 * entry_bytes + entry_bytes / 2;  // room for three
  auto cache = open(max_bytes);
  std::map<char, fs::path> path;
  auto store = [&](char c) {
    const RunResult r = run(*cache, with_text(text(c)), stages);
    EXPECT_EQ(state_of(r, "shout"), "miss") << c;
    path[c] = entry(*cache, "shout");
    const CacheInfo info = cache_info(cache_dir_);
    EXPECT_LE(info.bytes, max_bytes) << c;
    return info;
  };
  for (char c : {'a', 'b', 'c'})
    store(c);
  EXPECT_EQ(cache_info(cache_dir_).entries, 3u);
  const auto now = fs::file_time_type::clock::now();
  fs::last_write_time(path['a'], now - 300s);
  fs::last_write_time(path['b'], now - 200s);
  fs::last_write_time(path['c'], now - 100s);

  const RunResult hit = run(*cache, with_text(text('a')), stages);
  EXPECT_EQ(state_of(hit, "shout"), "hit");
  EXPECT_GT(fs::last_write_time(path['a']), fs::last_write_time(path['c']));

  // d does not fit beside a, b and c: b, now the least recently used, goes; a stays.
  EXPECT_EQ(store('d').entries, 3u);
  EXPECT_TRUE(fs::exists(path['a']));
  EXPECT_FALSE(fs::exists(path['b']));
  EXPECT_TRUE(fs::exists(path['c']));
  EXPECT_TRUE(fs::exists(path['d']));
  // e: then c.
  EXPECT_EQ(store('e').entries, 3u);
  EXPECT_TRUE(fs::exists(path['a']));
  EXPECT_FALSE(fs::exists(path['c']));
  EXPECT_TRUE(fs::exists(path['d']));
  EXPECT_TRUE(fs::exists(path['e']));
  EXPECT_EQ(*runs_, 5);  // a, b, c, d, e; the hit did not run
}

// A bound smaller than one bake's entries: the stores of the bake that follow a hit must not
// remove the entry it was answered from before a later stage has read its payload (that used to be
// reported as a corrupt entry and recomputed the whole bake). Two 4 KB outputs a and b read by an
// uncached sink; a is a hit, b a miss under a bound of 1.5 entries.
TEST_F(DiskCacheTest, StoresDoNotRemoveTheEntriesTheRunIsAnsweredFrom) {
  auto make = [](const std::string& name, const std::string& out) {
    Stage s;
    s.name = name;
    s.inputs = {"text"};
    s.outputs = {out};
    s.run = [out](StageContext& ctx) {
      ctx.output(out, std::string(4000, out[0]) + ctx.input<std::string>("text"));
    };
    return s;
  };
  Stage sink;
  sink.name = "sink";
  sink.inputs = {"a_out", "b_out"};
  sink.outputs = {"joined"};
  sink.cacheable = false;
  sink.run = [](StageContext& ctx) {
    ctx.output("joined", ctx.input<std::string>("a_out") + ctx.input<std::string>("b_out"));
  };
  {
    auto unbounded = open();
    run(*unbounded, with_text("t"), {make("a", "a_out")});
  }
  const uint64_t one = cache_info(cache_dir_).bytes;
  auto bounded = open(one * 3 / 2);
  const RunResult r = run(*bounded, with_text("t"), {make("a", "a_out"), make("b", "b_out"), sink});
  EXPECT_EQ(state_of(r, "a"), "hit");
  EXPECT_EQ(state_of(r, "b"), "miss");
  EXPECT_EQ(bounded->counts().corrupt, 0);
  EXPECT_EQ(bounded->counts().hits, 1);
  EXPECT_EQ(bounded->counts().misses, 1);
  EXPECT_FALSE(any_mentions(take_warnings(), "corrupt"));
  EXPECT_EQ(r.artifacts.get<std::string>("joined"),
            std::string(4000, 'a') + "t" + std::string(4000, 'b') + "t");
  // Pruned by the next store, once the entry is no longer in use by a running bake.
  EXPECT_TRUE(fs::exists(entry(*bounded, "a")));
}

// A scene render bakes its fabrics one after another through one cache: the assets it has
// already chosen (keep_file) stay however small the bound, while an asset of an earlier render is
// pruned as usual.
TEST_F(DiskCacheTest, KeptFilesStayWhenTheBoundPrunes) {
  const fs::path assets = fs::path(cache_dir_) / kAssetFolder;
  fs::create_directories(assets);
  spit(assets / "chosen.cbk", std::string(5000, 'c'));
  spit(assets / "other.cbk", std::string(5000, 'o'));
  const auto now = fs::file_time_type::clock::now();
  fs::last_write_time(assets / "chosen.cbk", now - 600s);  // the oldest: first to go otherwise
  fs::last_write_time(assets / "other.cbk", now - 300s);
  auto cache = open(1);
  cache->keep_file((assets / "chosen.cbk").string());
  run(*cache, with_text("t"), {shout_stage(runs_)});  // a store enforces the bound
  EXPECT_TRUE(fs::exists(assets / "chosen.cbk"));
  EXPECT_FALSE(fs::exists(assets / "other.cbk"));
  cache->enforce_bound();
  EXPECT_TRUE(fs::exists(assets / "chosen.cbk"));
  // Without keep_file the same bound takes it.
  auto fresh = open(1);
  fresh->enforce_bound();
  EXPECT_FALSE(fs::exists(assets / "chosen.cbk"));
}

// `cache info` / `cache prune` on a folder of entries, a scene-render asset (counted as stage
// "asset", bounded with the entries) and temporary files left by killed stores: prune removes the
// oldest files first until the rest fit, everything at 0, and only the temporary files older than
// an hour (a younger one may belong to a store in progress).
TEST_F(DiskCacheTest, PruneRemovesOldestFirstAllAtZeroAndOnlyStaleTemporaries) {
  {
    auto cache = open();
    for (char c : {'a', 'b', 'c'})
      run(*cache, with_text(std::string(100, c)), {shout_stage(runs_)});
  }
  const fs::path entries = fs::path(cache_dir_) / "entries";
  const fs::path assets = fs::path(cache_dir_) / kAssetFolder;
  fs::create_directories(assets);
  spit(assets / "scene.cbk", std::string(5000, 'z'));
  const fs::path old_tmp = entries / ".shout-old.entry.tmp-Ab12Cd";
  const fs::path new_tmp = entries / ".shout-new.entry.tmp-Ef34Gh";
  const fs::path old_asset_tmp = assets / ".scene.cbk.tmp-Zz99Yy";
  spit(old_tmp, "partial");
  spit(new_tmp, "partial");
  spit(old_asset_tmp, "partial");
  const auto now = fs::file_time_type::clock::now();
  fs::last_write_time(old_tmp, now - 2h);
  fs::last_write_time(new_tmp, now - 10min);
  fs::last_write_time(old_asset_tmp, now - 3h);
  // Recency: the asset, then the entries in the order a, b, c.
  fs::last_write_time(assets / "scene.cbk", now - 400s);
  std::vector<fs::path> by_age;
  for (const auto& e : fs::directory_iterator(entries))
    if (e.path().extension() == ".entry") by_age.push_back(e.path());
  ASSERT_EQ(by_age.size(), 3u);
  for (std::size_t k = 0; k < by_age.size(); ++k)
    fs::last_write_time(by_age[k], now - std::chrono::seconds(300 - 100 * k));

  const CacheInfo info = cache_info(cache_dir_);
  EXPECT_EQ(info.entries, 4u);
  EXPECT_EQ(info.temporary_files, 3u);
  ASSERT_EQ(info.per_stage.count("shout"), 1u);
  ASSERT_EQ(info.per_stage.count("asset"), 1u);
  EXPECT_EQ(info.per_stage.at("shout").first, 3u);
  EXPECT_EQ(info.per_stage.at("asset"), std::make_pair(uint64_t(1), uint64_t(5000)));
  EXPECT_EQ(info.bytes, info.per_stage.at("shout").second + 5000);
  const uint64_t entry_bytes = info.per_stage.at("shout").second / 3;

  // Everything fits: no entry goes; the temporaries older than an hour do.
  PruneResult p = prune_cache(cache_dir_, info.bytes);
  EXPECT_EQ(p.removed_entries, 0u);
  EXPECT_EQ(p.kept_entries, 4u);
  EXPECT_EQ(p.kept_bytes, info.bytes);
  EXPECT_FALSE(fs::exists(old_tmp));
  EXPECT_FALSE(fs::exists(old_asset_tmp));
  EXPECT_TRUE(fs::exists(new_tmp));
  EXPECT_EQ(cache_info(cache_dir_).temporary_files, 1u);

  // One byte too many: the oldest file (the asset) goes, and only it.
  p = prune_cache(cache_dir_, info.bytes - 1);
  EXPECT_EQ(p.removed_entries, 1u);
  EXPECT_EQ(p.removed_bytes, 5000u);
  EXPECT_EQ(p.kept_entries, 3u);
  EXPECT_FALSE(fs::exists(assets / "scene.cbk"));
  // Room for one entry: a and b go, c (the most recent) stays.
  p = prune_cache(cache_dir_, entry_bytes);
  EXPECT_EQ(p.removed_entries, 2u);
  EXPECT_EQ(p.kept_entries, 1u);
  EXPECT_FALSE(fs::exists(by_age[0]));
  EXPECT_FALSE(fs::exists(by_age[1]));
  EXPECT_TRUE(fs::exists(by_age[2]));
  // 0: everything.
  p = prune_cache(cache_dir_, 0);
  EXPECT_EQ(p.removed_entries, 1u);
  EXPECT_EQ(p.kept_entries, 0u);
  EXPECT_EQ(p.kept_bytes, 0u);
  const CacheInfo empty = cache_info(cache_dir_);
  EXPECT_EQ(empty.entries, 0u);
  EXPECT_EQ(empty.bytes, 0u);
  EXPECT_TRUE(fs::exists(new_tmp));  // still younger than an hour

  // Not a folder: Error(Input).
  spit(dir_ / "file", "x");
  try {
    cache_info((dir_ / "file").string());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
  }
}

// Removing the entries a run answered from (after CachedValuesInvalid) takes exactly those: the
// entry a stage of the run stored is kept; a second call finds none.
TEST_F(DiskCacheTest, DiscardHitsRemovesOnlyTheEntriesAnsweredFrom) {
  auto cache = open();
  run(*cache, with_text("hello"), {shout_stage(runs_)});
  const RunResult r = run(*cache, with_text("hello"), {shout_stage(runs_), measure_stage()});
  EXPECT_EQ(state_of(r, "shout"), "hit");
  EXPECT_EQ(state_of(r, "measure"), "miss");
  const fs::path shout = entry(*cache, "shout"), measure = entry(*cache, "measure");
  take_warnings();
  EXPECT_TRUE(cache->discard_hits("a check failed"));
  EXPECT_FALSE(fs::exists(shout));
  EXPECT_TRUE(fs::exists(measure));
  EXPECT_EQ(cache->counts().corrupt, 1);
  EXPECT_TRUE(any_mentions(take_warnings(), shout.string()));
  EXPECT_FALSE(cache->discard_hits("again"));
}

// A folder that cannot be created (its parent is a regular file) is warned about, naming it, and
// the cache is off: loads and stores are misses, nothing throws, and bakes run uncached.
TEST_F(DiskCacheTest, UncreatableFolderLeavesTheCacheOff) {
  spit(dir_ / "file", "x");
  const std::string bad = (dir_ / "file" / "cache").string();
  std::unique_ptr<DiskCache> cache;
  ASSERT_NO_THROW(cache = open(kDefaultCacheMaxBytes, bad));
  EXPECT_FALSE(cache->enabled());
  EXPECT_TRUE(any_mentions(take_warnings(), bad));

  const Stage shout = shout_stage(runs_);
  const Artifacts available = with_text("hello");
  Artifacts produced;
  EXPECT_FALSE(cache->load(shout, available, produced));
  produced.put("shout", shouted("hello"));
  EXPECT_FALSE(cache->store(shout, available, produced));

  const std::vector<Stage> stages = {shout, sink_stage()};
  for (int k = 0; k < 2; ++k) {
    RunResult r;
    ASSERT_NO_THROW(r = run(*cache, with_text("hello"), stages));
    EXPECT_EQ(r.artifacts.get<std::string>("result"), shouted("hello"));
    EXPECT_EQ(state_of(r, "shout"), "uncached");
  }
  EXPECT_EQ(*runs_, 2);
  EXPECT_EQ(cache->counts().hits, 0);
  EXPECT_EQ(cache->counts().misses, 0);
  EXPECT_FALSE(fs::exists(bad));
}

// --cache-max-size values as documented (K/M/G/T are powers of 1024, an optional "B" or "iB").
TEST(CacheSize, ParsesTheDocumentedForms) {
  EXPECT_EQ(parse_size("500M", "--cache-max-size"), uint64_t(500) << 20);
  EXPECT_EQ(parse_size("10G", "--cache-max-size"), uint64_t(10) << 30);
  EXPECT_EQ(parse_size("1.5GiB", "--cache-max-size"), uint64_t(3) << 29);
  EXPECT_EQ(parse_size("123456", "--cache-max-size"), 123456u);
  EXPECT_EQ(parse_size("4K", "--cache-max-size"), 4096u);
  EXPECT_EQ(parse_size("2T", "--cache-max-size"), uint64_t(2) << 40);
  EXPECT_EQ(parse_size("64KB", "--cache-max-size"), uint64_t(64) << 10);
  EXPECT_EQ(parse_size("100B", "--cache-max-size"), 100u);
  EXPECT_EQ(parse_size("0", "--cache-max-size"), 0u);
}

// Anything else is a usage error naming the option and the text.
TEST(CacheSize, RefusesOtherTextNamingTheOption) {
  // Also what std::stod alone would take: hexadecimal, an exponent, spaces, a doubled suffix, a
  // fraction of a byte.
  for (const std::string text :
       {"abc", "-1", "10X", "", "0x10", "1e3", " 5M", "5M ", "5bb", "1.5", "1.", ".5G", "+5"}) {
    try {
      parse_size(text, "--cache-max-size");
      ADD_FAILURE() << "'" << text << "' accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Usage) << text;
      EXPECT_NE(std::string(e.what()).find("--cache-max-size"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("'" + text + "'"), std::string::npos) << e.what();
    }
  }
}

// The cache folder: --cache wins, else $CLOTHBAKE_CACHE, else none (an empty variable is none).
TEST(CacheDir, OptionWinsThenTheEnvironmentThenNone) {
  const char* saved = std::getenv("CLOTHBAKE_CACHE");
  const std::optional<std::string> restore =
      saved ? std::optional<std::string>(saved) : std::nullopt;
  ::setenv("CLOTHBAKE_CACHE", "/from/env", 1);
  EXPECT_EQ(cache_dir_from("/from/option"), "/from/option");
  EXPECT_EQ(cache_dir_from(""), "/from/env");
  ::setenv("CLOTHBAKE_CACHE", "", 1);
  EXPECT_EQ(cache_dir_from(""), "");
  ::unsetenv("CLOTHBAKE_CACHE");
  EXPECT_EQ(cache_dir_from(""), "");
  EXPECT_EQ(cache_dir_from("/from/option"), "/from/option");
  if (restore) ::setenv("CLOTHBAKE_CACHE", restore->c_str(), 1);
}

}  // namespace

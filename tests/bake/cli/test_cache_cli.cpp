// The content-keyed stage cache end to end (`clothbake bake --cache`, `clothbake cache`): a second
// bake is all hits with the same bytes; an albedo-only change reuses every ray-casting, cluster,
// table and compression stage and gives the bytes of an uncached bake; a corrupted entry is
// detected, removed and recomputed; an unusable cache is warned about and bypassed; concurrent
// bakes of one key agree; a bake killed while storing leaves no torn entry; the size bound holds;
// scene renders bake their fabrics through the same cache.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <xxhash.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "bake/cache/codec.hpp"
#include "bake/pipeline/artifacts.hpp"
#include "bake/stages/cache_support.hpp"
#include "cluster/visibility_clusters.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/asg.hpp"
#include "tests/support/files.hpp"
#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;
using clothbake::test_support::CliRun;
using clothbake::test_support::clothbake_executable;
using clothbake::test_support::run_clothbake;

namespace {

const char* kFabric = R"(name = "tiny"
[weave]
name = "twill2/1"
[[yarn]]
name = "warp"
color = [0.05, 0.09, 0.26]
[[yarn]]
name = "weft"
[bake]
resolution = 16
parallax_dirs = 4
visibility_dirs = 4
radiance_dirs = 6
clusters = 2
)";

using clothbake::test_support::slurp;

class Cache : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake_cache_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "f.toml") << kFabric;
  }
  void TearDown() override { fs::remove_all(dir_); }

  // bake f.toml -o OUT [--cache DIR] --json; returns the report (code checked).
  nlohmann::json bake(const std::string& out, bool cached = true, CliRun* run = nullptr) {
    std::vector<std::string> args = {
        "bake", (dir_ / "f.toml").string(), "-o", (dir_ / out).string(), "--json", "--quiet"};
    if (cached) args.insert(args.end(), {"--cache", (dir_ / "cache").string()});
    CliRun r = run_clothbake(args);
    if (run) *run = r;
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json{};
  }
  static std::map<std::string, std::string> cache_states(const nlohmann::json& report) {
    std::map<std::string, std::string> out;
    for (const auto& s : report["stages"])
      out[s["name"]] = s["cache"];
    return out;
  }
  std::vector<fs::path> entries(const std::string& stage = "") const {
    std::vector<fs::path> out;
    for (const auto& e : fs::directory_iterator(dir_ / "cache" / "entries"))
      if (e.path().filename().string().rfind(stage, 0) == 0 && e.path().extension() == ".entry")
        out.push_back(e.path());
    return out;
  }
  fs::path dir_;
};

const std::vector<std::string> kReused = {"parallax", "visibility", "cluster", "tables",
                                          "compress"};

TEST_F(Cache, SecondBakeIsAllHitsWithTheSameBytes) {
  const auto first = bake("a.cbk");
  for (const auto& [stage, state] : cache_states(first))
    EXPECT_EQ(state, stage == "load_fabric" || stage == "write" ? "uncached" : "miss") << stage;
  const auto second = bake("b.cbk");
  for (const auto& [stage, state] : cache_states(second))
    EXPECT_EQ(state, stage == "load_fabric" || stage == "write" ? "uncached" : "hit") << stage;
  bake("plain.cbk", false);
  EXPECT_EQ(slurp(dir_ / "a.cbk"), slurp(dir_ / "plain.cbk"));
  EXPECT_EQ(slurp(dir_ / "b.cbk"), slurp(dir_ / "plain.cbk"));
  EXPECT_EQ(second["cache"]["hits"], 7);
}

TEST_F(Cache, AlbedoOnlyChangeReusesTheGeometryStages) {
  bake("a.cbk");
  std::string text = kFabric;
  text.replace(text.find("0.05, 0.09, 0.26"), 16, "0.50, 0.10, 0.02");
  std::ofstream(dir_ / "f.toml") << text;
  const auto report = bake("b.cbk");
  const auto states = cache_states(report);
  for (const auto& s : kReused)
    EXPECT_EQ(states.at(s), "hit") << s;
  EXPECT_EQ(states.at("fabric_records"), "miss");  // the yarn colours are in the records
  bake("plain.cbk", false);
  EXPECT_EQ(slurp(dir_ / "b.cbk"), slurp(dir_ / "plain.cbk"));
  EXPECT_NE(slurp(dir_ / "a.cbk"), slurp(dir_ / "b.cbk"));

  // A geometry change (roughness) is a miss for the tables.
  text.replace(text.find("name = \"weft\""), 13, "name = \"weft\"\nroughness = 0.55");
  std::ofstream(dir_ / "f.toml") << text;
  EXPECT_EQ(cache_states(bake("c.cbk")).at("tables"), "miss");
}

// Evicted entries (prune takes the least recently used out one by one) are recomputed from the
// entries still cached: for every stage, the entries after it are removed, so every cached output
// a computing stage reads is decoded. An entry every bake writes must pass its own decode checks:
// nothing is reported corrupt, only the removed stages are stored, and the asset is unchanged.
TEST_F(Cache, EvictedEntriesAreRebuiltFromTheCachedOnes) {
  const std::vector<std::string> order = {"fabric_records", "feature_maps", "parallax",
                                          "visibility",     "cluster",      "tables"};
  bake("a.cbk");
  for (std::size_t kept = 1; kept <= order.size(); ++kept) {
    bake("full.cbk");  // every entry back
    for (std::size_t k = kept; k < order.size(); ++k)
      for (const auto& e : entries(order[k]))
        fs::remove(e);
    for (const auto& e : entries("compress"))
      fs::remove(e);
    const auto report = bake("b.cbk");
    const auto states = cache_states(report);
    EXPECT_EQ(states.at(order[kept - 1]), "hit") << order[kept - 1];
    EXPECT_EQ(report["cache"]["corrupt"], 0) << order[kept - 1] << report["warnings"].dump();
    EXPECT_EQ(report["cache"]["stored"], int(order.size() - kept + 1))
        << order[kept - 1] << report["warnings"].dump();
    EXPECT_EQ(slurp(dir_ / "b.cbk"), slurp(dir_ / "a.cbk")) << order[kept - 1];
  }
}

// A flipped byte in a payload, in the index, or a truncated entry: detected, removed, recomputed;
// the asset equals an uncached bake.
TEST_F(Cache, CorruptedEntriesAreRecomputedNeverUsed) {
  bake("plain.cbk", false);
  bake("a.cbk");
  const std::string good = slurp(dir_ / "plain.cbk");
  for (int kind = 0; kind < 3; ++kind) {
    for (const std::string stage : {"parallax", "feature_maps"}) {
      ASSERT_EQ(entries(stage).size(), 1u);
      const fs::path entry = entries(stage)[0];
      std::string bytes = slurp(entry);
      if (kind == 0) bytes[72] ^= 0x10;  // payload (the first starts at 64, after the pad)
      if (kind == 1) bytes[bytes.size() - 30] ^= 0x10;  // index
      if (kind == 2) bytes.resize(bytes.size() / 2);    // truncated
      std::ofstream(entry, std::ios::binary | std::ios::trunc) << bytes;
    }
    CliRun run;
    const auto report = bake("b.cbk", true, &run);
    EXPECT_NE(report["warnings"].dump().find("is corrupt"), std::string::npos) << kind << run.out;
    EXPECT_GE(report["cache"]["corrupt"].get<int>(), 1) << kind;
    // Hits and stores are those of the attempt that wrote the asset: every cacheable stage once.
    EXPECT_EQ(report["cache"]["hits"].get<int>() + report["cache"]["stored"].get<int>(), 7)
        << kind << report["cache"].dump();
    EXPECT_EQ(slurp(dir_ / "b.cbk"), good) << kind;
    fs::remove(dir_ / "b.cbk");
    // Recomputed and stored again: the next bake is all hits, no warning.
    const auto again = bake("c.cbk", true, &run);
    EXPECT_EQ(again["cache"]["hits"], 7) << kind;
    EXPECT_EQ(again["warnings"].size(), 0u) << again["warnings"];
    fs::remove(dir_ / "c.cbk");
  }
}

// An entry rewritten with recomputed checksums, as an adversary would: the outputs by name, each
// with its codec tag and payload (docs/batch.md, "Entries").
struct EntryFile {
  std::string header;                               // 32 bytes: magic, schema, count, key
  std::vector<std::array<std::string, 3>> outputs;  // name, tag, payload

  explicit EntryFile(const std::string& bytes) : header(bytes.substr(0, 32)) {
    const auto u64 = [&](std::size_t at) {
      uint64_t v;
      std::memcpy(&v, bytes.data() + at, 8);
      return v;
    };
    const uint64_t index = u64(bytes.size() - 24), end = bytes.size() - 24;
    for (uint64_t p = index; p < end;) {
      std::array<std::string, 3> o;
      for (int k = 0; k < 2; ++k) {
        o[k] = bytes.substr(p + 8, u64(p));
        p += 8 + o[k].size();
      }
      o[2] = bytes.substr(u64(p), u64(p + 8));
      p += 24;
      outputs.push_back(o);
    }
  }
  std::string& payload(const std::string& name) {
    for (auto& o : outputs)
      if (o[0] == name) return o[2];
    throw std::runtime_error("no output " + name);
  }
  std::string bytes() const {
    const auto put = [](std::string& s, uint64_t v) { s.append(reinterpret_cast<char*>(&v), 8); };
    std::string out = header, index;
    for (const auto& o : outputs) {
      out.append((64 - out.size() % 64) % 64, '\0');
      put(index, o[0].size());
      index += o[0];
      put(index, o[1].size());
      index += o[1];
      put(index, out.size());
      put(index, o[2].size());
      put(index, XXH3_64bits(o[2].data(), o[2].size()));
      out += o[2];
    }
    const uint64_t at = out.size();
    out += index;
    put(out, at);
    put(out, index.size());
    put(out, XXH3_64bits((header + index).data(), header.size() + index.size()));
    return out;
  }
};

// Decodes `payload` with the codec of `tag`, lets `edit` change the value, encodes it again.
template <class T>
std::string edited(const std::string& tag, const std::string& payload,
                   const std::function<void(T&)>& edit) {
  const clothbake::cache::Codecs codecs = clothbake::stages::artifact_codecs();
  const clothbake::cache::Codec* codec = codecs.for_tag(tag);
  clothbake::pipeline::Artifacts a;
  clothbake::cache::ByteReader r(reinterpret_cast<const std::byte*>(payload.data()),
                                 payload.size());
  codec->decode(r, a, "v");
  T value = a.get<T>("v");
  edit(value);
  clothbake::pipeline::Artifacts b;
  b.put("v", value);
  clothbake::cache::ByteWriter w;
  codec->encode(b, "v", w);
  return std::string(reinterpret_cast<const char*>(w.bytes().data()), w.bytes().size());
}

// Entries whose checksums were recomputed after an edit are checked like values from a file: a
// bad one is warned about naming it, removed, and its stage recomputed; the asset is the uncached
// one (it used to be exit 0 with an asset validate rejects, exit 0 with other metadata, or exit 2
// naming no entry and keeping it, so that every later bake failed). Deep CBOR (a stack overflow
// before), a section shape that overflows 64 bits (exit 4), a claim of 2^27 strings and a sparse
// 2 GiB entry (4.2 GB each) and a FIFO in place of an entry (a hang) are corrupt entries too, in
// bounded memory.
TEST_F(Cache, CraftedEntriesWithRecomputedChecksumsAreCheckedLikeFiles) {
  using clothbake::cluster::VisibilityClusters;
  bake("plain.cbk", false);
  bake("a.cbk");
  const std::string good = slurp(dir_ / "plain.cbk");
  struct Case {
    std::string name, stage, output;
    std::function<std::string(const std::string& tag, const std::string& payload)> payload;
    std::vector<std::string> rerun;  // stages whose entries are removed, so that they read it
  };
  using Sections = std::vector<clothbake::formats::Section>;
  const auto sections = [](std::function<void(Sections&)> edit) {
    return [edit](const std::string& tag, const std::string& payload) {
      return edited<Sections>(tag, payload, edit);
    };
  };
  const auto cbor = [](const std::string& bytes) {
    return [bytes](const std::string&, const std::string&) {
      std::string out(8, '\0');
      const uint64_t n = bytes.size();
      std::memcpy(out.data(), &n, 8);
      return out + bytes;
    };
  };
  const std::vector<uint8_t> array = nlohmann::json::to_cbor(nlohmann::json::array({1, 2}));
  const Case cases[] = {
      {"wrong resolution",
       "cluster",
       "section/clusters",
       sections([](Sections& v) {
         for (auto& s : v)
           if (s.dims.size() == 2) s.dims = {8, 8}, s.payload.resize(64 * s.payload.size() / 256);
       }),
       {}},
      {"label out of range",
       "cluster",
       "clusters",
       [](const std::string& tag, const std::string& payload) {
         return edited<VisibilityClusters>(tag, payload,
                                           [](VisibilityClusters& c) { c.labels[5] = 200; });
       },
       {"tables", "compress"}},
      {"NaN lobe",
       "visibility",
       "visibility/asg_params",
       [](const std::string& tag, const std::string& payload) {
         using Asgs = std::vector<clothbake::model::AsgParams<float>>;
         return edited<Asgs>(tag, payload, [](Asgs& v) { v[3].lambda = std::nanf(""); });
       },
       {"cluster", "tables", "compress"}},
      {"metadata of another type",
       "cluster",
       "metadata/clusters",
       cbor(std::string(array.begin(), array.end())),
       {}},
      {"deep CBOR", "cluster", "metadata/clusters", cbor(std::string(100000, '\x81') + '\0'), {}},
      {"section shape overflow",
       "parallax",
       "section/parallax",
       sections([](Sections& v) {
         v[0].dims = {0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu};
       }),
       {}},
  };
  const std::map<std::string, std::string> originals = {
      {"cluster", slurp(entries("cluster")[0])},
      {"visibility", slurp(entries("visibility")[0])},
      {"parallax", slurp(entries("parallax")[0])}};
  for (const Case& c : cases) {
    const fs::path entry = entries(c.stage)[0];
    EntryFile file(originals.at(c.stage));
    for (auto& o : file.outputs)
      if (o[0] == c.output) o[2] = c.payload(o[1], o[2]);
    std::ofstream(entry, std::ios::binary | std::ios::trunc) << file.bytes();
    for (const auto& stage : c.rerun)
      fs::remove(entries(stage)[0]);
    CliRun run;
    const std::string warnings = bake("b.cbk", true, &run)["warnings"].dump();
    ASSERT_EQ(run.code, 0) << c.name << ": " << run.err;
    EXPECT_NE(warnings.find("cache entry " + entry.string() + " is corrupt"), std::string::npos)
        << c.name << ": " << warnings;
    EXPECT_EQ(slurp(dir_ / "b.cbk"), good) << c.name;
    EXPECT_LT(run.max_rss_kb, 1 << 20) << c.name;
    // The bad entry is gone and stored anew: the next bake has no warning.
    const auto again = bake("c.cbk", true, &run);
    EXPECT_EQ(again["warnings"].size(), 0u) << c.name << ": " << again["warnings"];
    EXPECT_EQ(slurp(dir_ / "c.cbk"), good) << c.name;
  }

  // Declared sizes are checked before anything is allocated: a claim of 2^27 strings (the
  // compress stage's superseded sections) and a sparse 2 GiB entry whose index claims 2 GiB.
  const auto expect_recomputed = [&](const std::string& out) {
    CliRun run;
    const std::string warnings = bake(out, true, &run)["warnings"].dump();
    EXPECT_NE(warnings.find("is corrupt"), std::string::npos) << out << ": " << warnings;
    EXPECT_LT(run.max_rss_kb, 1 << 20) << out;
    EXPECT_EQ(slurp(dir_ / out), good) << out;
  };
  {
    const fs::path entry = entries("compress")[0];
    EntryFile file(slurp(entry));
    std::string claim(8, '\0');
    const uint64_t n = uint64_t(1) << 27;
    std::memcpy(claim.data(), &n, 8);
    file.payload("supersedes/compress") = claim;
    std::ofstream(entry, std::ios::binary | std::ios::trunc) << file.bytes();
    expect_recomputed("d.cbk");
  }
  {
    const fs::path entry = entries("parallax")[0];
    const uint64_t size = uint64_t(2) << 30;
    fs::resize_file(entry, size);  // sparse: the trailer says the index is everything after 32
    std::fstream f(entry, std::ios::binary | std::ios::in | std::ios::out);
    const uint64_t trailer[3] = {32, size - 24 - 32, 0};
    f.seekp(std::streamoff(size - 24));
    f.write(reinterpret_cast<const char*>(trailer), sizeof trailer);
    f.close();
    expect_recomputed("e.cbk");
  }
  {
    const fs::path entry = entries("visibility")[0];
    fs::remove(entry);
    ASSERT_EQ(::mkfifo(entry.c_str(), 0600), 0);
    const CliRun run = clothbake::test_support::detail::spawn(
        {"/usr/bin/timeout", "60", clothbake_executable(), "bake", (dir_ / "f.toml").string(), "-o",
         (dir_ / "f.cbk").string(), "--cache", (dir_ / "cache").string()});
    EXPECT_EQ(run.code, 0) << run.err;  // timeout's 124 when the FIFO blocks
    EXPECT_NE(run.err.find("not a regular file"), std::string::npos) << run.err;
    EXPECT_TRUE(fs::is_regular_file(entries("visibility")[0]));
    EXPECT_EQ(slurp(dir_ / "f.cbk"), good);
  }
}

TEST_F(Cache, UnusableCacheIsWarnedAboutAndBypassed) {
  std::ofstream(dir_ / "cache") << "a file, not a folder";
  CliRun run;
  const auto report = bake("a.cbk", true, &run);
  EXPECT_NE(report["warnings"].dump().find("baking without the cache"), std::string::npos)
      << run.out;
  EXPECT_EQ(report["cache"]["enabled"], false);
  bake("plain.cbk", false);
  EXPECT_EQ(slurp(dir_ / "a.cbk"), slurp(dir_ / "plain.cbk"));
}

TEST_F(Cache, ConcurrentBakesOfOneKeyAgree) {
  bake("plain.cbk", false);
  std::vector<std::thread> threads;
  std::vector<CliRun> runs(3);
  const std::vector<std::string> outs = {"c0.cbk", "c1.cbk", "c2.cbk"};
  for (int i = 0; i < 3; ++i)
    threads.emplace_back([&, i] {
      runs[i] = run_clothbake({"bake", (dir_ / "f.toml").string(), "-o", (dir_ / outs[i]).string(),
                               "--quiet", "--json", "--cache", (dir_ / "cache").string()});
    });
  for (auto& t : threads)
    t.join();
  int stored = 0;
  for (int i = 0; i < 3; ++i) {
    ASSERT_EQ(runs[i].code, 0) << runs[i].err;
    EXPECT_EQ(slurp(dir_ / outs[i]), slurp(dir_ / "plain.cbk"));
    stored += nlohmann::json::parse(runs[i].out)["cache"]["stored"].get<int>();
  }
  EXPECT_EQ(stored, 7) << "each stage computed once across the three bakes";
  EXPECT_EQ(entries().size(), 7u);
}

// SIGKILL while an entry is being written (the sink pauses mid-write): only a temporary file is
// left, never a torn entry; the next bake is correct.
TEST_F(Cache, KilledStoreLeavesNoTornEntry) {
  const std::string exe = clothbake_executable();
  const std::string f = (dir_ / "f.toml").string(), out = (dir_ / "a.cbk").string(),
                    cache = (dir_ / "cache").string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("CLOTHBAKE_TEST_PAUSE_AFTER_BYTES", "2000", 1);
    ::execl(exe.c_str(), exe.c_str(), "bake", f.c_str(), "-o", out.c_str(), "--quiet", "--cache",
            cache.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool partial = false;
  for (int i = 0; i < 1000 && !partial; ++i) {
    std::error_code ec;
    if (fs::is_directory(dir_ / "cache" / "entries", ec))
      for (const auto& e : fs::directory_iterator(dir_ / "cache" / "entries", ec))
        if (e.path().filename().string()[0] == '.' && fs::file_size(e.path(), ec) >= 2000)
          partial = true;
    if (!partial) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(partial) << "the store never paused mid-write";
  EXPECT_FALSE(fs::exists(out));
  const auto info = run_clothbake({"cache", "info", cache, "--json"});
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["temporary_files"], 1);
  CliRun run;
  const auto report = bake("a.cbk", true, &run);
  EXPECT_EQ(report["warnings"].size(), 0u) << report["warnings"];
  bake("plain.cbk", false);
  EXPECT_EQ(slurp(dir_ / "a.cbk"), slurp(dir_ / "plain.cbk"));
  // Storing that entry again removed the killed store's temporary (its lock died with it).
  const auto after = run_clothbake({"cache", "info", cache, "--json"});
  EXPECT_EQ(nlohmann::json::parse(after.out)["temporary_files"], 0);
}

// `cache prune` removes old temporaries only when no live writer holds their flock.
TEST_F(Cache, PruneLeavesALockedTemporary) {
  bake("a.cbk");
  const fs::path temp = dir_ / "cache" / "entries" / ".parallax-0123.entry.tmp-Ab3xZ9";
  std::ofstream(temp) << "partial";
  const auto two_hours_ago = fs::file_time_type::clock::now() - std::chrono::hours(2);
  fs::last_write_time(temp, two_hours_ago);
  // This process stands for a live store: it holds the lock while the CLI prunes.
  const int fd = ::open(temp.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  CliRun r = run_clothbake({"cache", "prune", (dir_ / "cache").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(temp));
  ::close(fd);
  r = run_clothbake({"cache", "prune", (dir_ / "cache").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(temp));
}

TEST_F(Cache, SizeBoundAndPrune) {
  bake("a.cbk");
  const auto info = nlohmann::json::parse(
      run_clothbake({"cache", "info", (dir_ / "cache").string(), "--json"}).out);
  const uint64_t total = info["bytes"];
  ASSERT_GT(total, 0u);
  // A bound of half the total: the least recently used entries go, the rest fit.
  fs::remove_all(dir_ / "cache");
  bake("b.cbk", true);
  auto r = run_clothbake({"cache", "prune", (dir_ / "cache").string(), "--max-size",
                          std::to_string(total / 2), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto doc = nlohmann::json::parse(r.out);
  EXPECT_LE(doc["kept_bytes"].get<uint64_t>(), total / 2);
  EXPECT_GT(doc["removed_entries"].get<int>(), 0);
  // --cache-max-size bounds the cache during the bake.
  fs::remove_all(dir_ / "cache");
  CliRun run = run_clothbake({"bake", (dir_ / "f.toml").string(), "-o", (dir_ / "c.cbk").string(),
                              "--quiet", "--cache", (dir_ / "cache").string(), "--cache-max-size",
                              std::to_string(total / 2)});
  ASSERT_EQ(run.code, 0) << run.err;
  doc = nlohmann::json::parse(
      run_clothbake({"cache", "info", (dir_ / "cache").string(), "--json"}).out);
  EXPECT_LE(doc["bytes"].get<uint64_t>(), total / 2);
  r = run_clothbake({"cache", "prune", (dir_ / "cache").string(), "--all", "--json"});
  EXPECT_EQ(nlohmann::json::parse(r.out)["kept_entries"], 0);
  EXPECT_EQ(run_clothbake({"cache", "prune", (dir_ / "cache").string(), "--max-size", "lots"}).code,
            1);
}

// `clothbake render` with a `fabric =` object: the fabric is baked through the stage cache and the
// asset kept in CACHE/assets (byte-identical to a plain bake); a second render bakes nothing; a
// colour edit reuses every geometry stage and adds one asset; `cache info` counts the assets and
// `cache prune --all` removes them.
TEST_F(Cache, SceneRendersBakeTheirFabricsThroughTheStageCache) {
  std::ofstream(dir_ / "scene.toml")
      << "[camera]\nposition = [0, 0, 2]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov_deg = 30\n"
         "resolution = [8, 6]\n[[light]]\ntype = \"point\"\nposition = [0.5, 0.5, 1.5]\n"
         "intensity = 3\n[[object]]\nshape = \"plane\"\ncenter = [0, 0, 0]\nnormal = [0, 0, 1]\n"
         "tangent = [1, 0, 0]\nsize = [2, 2]\nfabric = \"f.toml\"\n";
  auto render = [&](const std::string& out) {
    const CliRun r =
        run_clothbake({"render", (dir_ / "scene.toml").string(), "-o", (dir_ / out).string(),
                       "--spp", "1", "--cache", (dir_ / "cache").string(), "--json"});
    EXPECT_EQ(r.code, 0) << r.err;
  };
  auto assets = [&] {
    std::vector<fs::path> out;
    for (const auto& e : fs::directory_iterator(dir_ / "cache" / "assets"))
      if (e.path().extension() == ".cbk") out.push_back(e.path());
    return out;
  };
  render("a.exr");
  ASSERT_EQ(assets().size(), 1u);
  for (const std::string stage : {"fabric_records", "feature_maps", "parallax", "visibility",
                                  "cluster", "tables", "compress"})
    EXPECT_EQ(entries(stage + "-").size(), 1u) << stage;
  bake("plain.cbk", false);
  const fs::path first = assets()[0];
  EXPECT_EQ(slurp(first), slurp(dir_ / "plain.cbk"));

  const auto before = fs::last_write_time(first);
  render("b.exr");  // nothing to bake
  EXPECT_EQ(assets().size(), 1u);
  EXPECT_EQ(entries().size(), 7u);
  EXPECT_EQ(slurp(dir_ / "a.exr"), slurp(dir_ / "b.exr"));
  EXPECT_GE(fs::last_write_time(first), before);

  std::string text = kFabric;
  text.replace(text.find("0.05, 0.09, 0.26"), 16, "0.50, 0.10, 0.02");
  std::ofstream(dir_ / "f.toml") << text;
  render("c.exr");
  EXPECT_EQ(assets().size(), 2u);
  for (const auto& s : kReused)
    EXPECT_EQ(entries(s + "-").size(), 1u) << s;  // reused, not baked again
  EXPECT_EQ(entries("fabric_records-").size(), 2u);
  bake("plain2.cbk", false);
  bool found = false;
  for (const auto& a : assets())
    found |= a != first && slurp(a) == slurp(dir_ / "plain2.cbk");
  EXPECT_TRUE(found);

  const auto info = nlohmann::json::parse(
      run_clothbake({"cache", "info", (dir_ / "cache").string(), "--json"}).out);
  EXPECT_EQ(info["stages"]["asset"]["entries"], 2);
  EXPECT_EQ(info["entries"], 9 + 2);
  const CliRun pruned = run_clothbake({"cache", "prune", (dir_ / "cache").string(), "--all"});
  EXPECT_EQ(pruned.code, 0) << pruned.err;
  EXPECT_TRUE(assets().empty());
}

}  // namespace

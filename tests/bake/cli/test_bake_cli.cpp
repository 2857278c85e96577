// The clothbake executable end to end: bake, info, validate, export; determinism across thread
// counts and runs; the documented exit codes and messages for bad inputs; SIGKILL, SIGINT and
// SIGTERM mid-write and a file-size limit (disk full) leave the previous asset intact (and, but
// for SIGKILL, no temporary file; the next bake removes a killed one's).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "common/image_io/image_io.hpp"
#include "formats/reader/layout.hpp"
#include "tests/support/files.hpp"

namespace {

namespace fs = std::filesystem;
const std::string kClothbake = CLOTHBAKE_BINARY_DIR "/bin/clothbake";

struct Outcome {
  int code = -1;
  std::string out, err;
};

struct SpawnOptions {
  std::vector<std::string> env;  // NAME=VALUE added to the environment
  long file_size_limit = -1;     // RLIMIT_FSIZE in bytes (SIGXFSZ ignored)
};

using clothbake::test_support::slurp;

pid_t spawn(const fs::path& dir, const std::vector<std::string>& args,
            const SpawnOptions& options) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  const int out = ::open((dir / "stdout.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int err = ::open((dir / "stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(out, 1);
  ::dup2(err, 2);
  ::chdir(dir.c_str());
  // A shell may start the tests with SIGINT ignored, which clothbake would keep so.
  ::signal(SIGINT, SIG_DFL);
  ::signal(SIGTERM, SIG_DFL);
  for (const auto& e : options.env)
    ::putenv(const_cast<char*>(e.c_str()));
  if (options.file_size_limit >= 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    struct rlimit limit {
      rlim_t(options.file_size_limit), rlim_t(options.file_size_limit)
    };
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  std::vector<char*> argv{const_cast<char*>(kClothbake.c_str())};
  for (const auto& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  ::execv(kClothbake.c_str(), argv.data());
  ::_exit(127);
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake-cli-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
    std::ofstream(dir_ / "fabric.toml") << "name = \"cli test\"\n"
                                           "[weave]\nname = \"twill2/1\"\n"
                                           "[[yarn]]\nname = \"warp\"\n"
                                           "[[yarn]]\nname = \"weft\"\n"
                                           "[bake]\nresolution = 64\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  Outcome run(const std::vector<std::string>& args, const SpawnOptions& options = {}) {
    const pid_t pid = spawn(dir_ / "io", prefix(args), options);
    int status = 0;
    ::waitpid(pid, &status, 0);
    Outcome r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = slurp(dir_ / "io" / "stdout.txt");
    r.err = slurp(dir_ / "io" / "stderr.txt");
    return r;
  }
  // Relative names resolve against the test directory.
  std::vector<std::string> prefix(const std::vector<std::string>& args) const {
    std::vector<std::string> out;
    for (const auto& a : args)
      out.push_back(a.rfind("@", 0) == 0 ? (dir_ / a.substr(1)).string() : a);
    return out;
  }
  std::string file(const std::string& name) const { return slurp(dir_ / name); }
  int interrupt_bake_mid_write(int signo, bool& partial);
  std::vector<std::string> others(const std::string& keep) const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string n = e.path().filename().string();
      if (n != keep && n != "io" && e.path().extension() != ".toml") names.push_back(n);
    }
    return names;
  }
  fs::path dir_;
};

#define EXPECT_IN(needle, haystack) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

TEST_F(Cli, BakeInfoValidateExport) {
  // Only this issue's stages: later stages (parallax, ...) have their own tests.
  Outcome r = run({"bake", "@fabric.toml", "-o", "@a.cbk", "--stages", "feature_maps", "--report",
                   "@report.json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // --quiet
  const auto report = nlohmann::json::parse(file("report.json"));
  EXPECT_EQ(report["stages"].size(), 4u);
  EXPECT_EQ(report["asset"]["size_bytes"], fs::file_size(dir_ / "a.cbk"));
  for (const auto& s : report["stages"]) {
    EXPECT_TRUE(s.contains("wall_seconds") && s.contains("cpu_seconds") &&
                s.contains("peak_rss_bytes"));
  }

  r = run({"info", "@a.cbk", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto info = nlohmann::json::parse(r.out);
  EXPECT_EQ(info["fabric_info"]["resolution"], 64);
  EXPECT_EQ(info["metadata"]["fabric"]["name"], "cli test");
  EXPECT_EQ(info["sections"].size(), 9u);
  EXPECT_EQ(info["content_hash"], report["asset"]["content_hash"]);
  r = run({"info", "@a.cbk"});
  EXPECT_EQ(r.code, 0);
  EXPECT_IN("yarn_id", r.out);
  // The text names the fabric, its yarns' colours and its sheen, lists the bake settings as
  // "key value" pairs (not a JSON object) and gives the size in binary units with the bytes.
  EXPECT_IN("name:     cli test", r.out);
  EXPECT_IN(" colour (", r.out);
  EXPECT_IN("sheen colour (", r.out);
  EXPECT_IN("resolution 64", r.out);
  EXPECT_EQ(r.out.find("bake:     {"), std::string::npos) << r.out;
  EXPECT_IN(" KiB (", r.out);

  r = run({"validate", "@a.cbk", "--json"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["valid"], true);

  r = run({"export", "@a.cbk", "--section", "normal", "-o", "@normal.exr"});
  ASSERT_EQ(r.code, 0) << r.err;
  const clothbake::Image normal = clothbake::read_image((dir_ / "normal.exr").string());
  EXPECT_EQ(normal.width, 64);
  EXPECT_EQ(normal.channels, 3);
  for (int y = 0; y < 64; y += 9)
    for (int x = 0; x < 64; x += 7) {
      const double len = std::hypot(normal.at(x, y, 0), normal.at(x, y, 1), normal.at(x, y, 2));
      EXPECT_NEAR(len, 1.0, 1e-5);
    }
  r = run({"export", "@a.cbk", "--section", "0x0104", "-o", "@ids.exr"});
  EXPECT_EQ(r.code, 0) << r.err;
  r = run({"export", "@a.cbk", "--section", "parallax", "-o", "@p.exr"});
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("no parallax section", r.err);
  r = run({"export", "@a.cbk", "--section", "height", "--index", "70", "-o", "@h.exr"});
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("out of range", r.err);
  r = run({"export", "@a.cbk", "--section", "height", "-o", "@a.cbk"});
  EXPECT_EQ(r.code, 2);
}

TEST_F(Cli, BytesIdenticalForThreads1And2AndRunToRun) {
  // Every stage (the default), on a small tile: the promise covers the whole bake.
  std::ofstream(dir_ / "small.toml") << "name = \"small\"\n[weave]\nname = \"twill2/1\"\n"
                                        "[[yarn]]\nname = \"warp\"\n[[yarn]]\nname = \"weft\"\n"
                                        "[bake]\nresolution = 16\n";
  Outcome r = run({"bake", "@small.toml", "-o", "@t1.cbk", "--threads", "1"});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(run({"bake", "@small.toml", "-o", "@t2.cbk", "--threads", "2"}).code, 0);
  ASSERT_EQ(run({"bake", "@small.toml", "-o", "@t2b.cbk", "--threads", "2"}).code, 0);
  EXPECT_EQ(file("t1.cbk"), file("t2.cbk"));
  EXPECT_EQ(file("t2.cbk"), file("t2b.cbk"));
  EXPECT_GT(file("t1.cbk").size(), 16u * 16u * 4u * 6u);
}

TEST_F(Cli, StageSelectionAndListing) {
  Outcome r = run({"bake", "@fabric.toml", "-o", "@r.cbk", "--stages", "fabric_records", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["asset"]["sections"].size(), 3u);
  r = run({"bake", "@fabric.toml", "-o", "@x.cbk", "--stages", "feature_maps,bogus"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("unknown stage 'bogus'", r.err);
  EXPECT_FALSE(fs::exists(dir_ / "x.cbk"));
  r = run({"bake", "--list-stages", "--json"});
  ASSERT_EQ(r.code, 0);
  EXPECT_GE(nlohmann::json::parse(r.out)["stages"].size(), 4u);
}

TEST_F(Cli, ListStagesPrintsTheRunOrder) {
  Outcome r = run({"bake", "--list-stages", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json listed = nlohmann::json::parse(r.out);
  std::vector<std::string> names;
  for (const auto& s : listed["stages"])
    names.push_back(s["name"]);
  EXPECT_EQ(names,
            (std::vector<std::string>{"load_fabric", "fabric_records", "feature_maps", "parallax",
                                      "visibility", "cluster", "tables", "compress", "write"}));
  // The same order as the stages of a bake's metadata (the order they ran in).
  r = run({"bake", "@fabric.toml", "-o", "@order.cbk", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(r.out);
  std::vector<std::string> ran;
  for (const auto& s : report["stages"])
    ran.push_back(s["name"]);
  EXPECT_EQ(ran, names);
}

TEST_F(Cli, BadOutputs) {
  // A directory.
  Outcome r = run({"bake", "@fabric.toml", "-o", "@io"});
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("is a directory", r.err);
  // A missing directory.
  r = run({"bake", "@fabric.toml", "-o", "@missing/a.cbk"});
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("does not exist", r.err);
  // An unwritable place.
  r = run({"bake", "@fabric.toml", "-o", "/proc/clothbake.cbk"});
  EXPECT_EQ(r.code, 2);
  // An existing file that is not an asset: refused, kept; replaced with --force.
  std::ofstream(dir_ / "notes.cbk") << "my notes";
  r = run({"bake", "@fabric.toml", "-o", "@notes.cbk"});
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("not a clothbake asset", r.err);
  EXPECT_IN("--force", r.err);
  EXPECT_EQ(file("notes.cbk"), "my notes");
  r = run({"bake", "@fabric.toml", "-o", "@notes.cbk", "--force", "--stages", "feature_maps"});
  EXPECT_EQ(r.code, 0) << r.err;
  // A bad report path fails before the bake.
  r = run({"bake", "@fabric.toml", "-o", "@b.cbk", "--report", "@missing/r.json"});
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "b.cbk"));
  // A missing fabric.
  r = run({"bake", "@nope.toml", "-o", "@b.cbk"});
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "b.cbk"));
}

TEST_F(Cli, DiskFullKeepsThePreviousAsset) {
  ASSERT_EQ(run({"bake", "@fabric.toml", "-o", "@a.cbk", "--stages", "feature_maps"}).code, 0);
  const std::string good = file("a.cbk");
  std::ofstream(dir_ / "big.toml") << "name = \"big\"\n[weave]\nname = \"plain\"\n"
                                      "[[yarn]]\nname = \"warp\"\n[[yarn]]\nname = \"weft\"\n"
                                      "[bake]\nresolution = 128\n";
  SpawnOptions limited;
  limited.file_size_limit = 60000;  // the 128^2 asset needs 88 kB (its maps, entropy-coded)
  const Outcome r = run({"bake", "@big.toml", "-o", "@a.cbk", "--stages", "feature_maps"}, limited);
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("File too large", r.err);
  EXPECT_EQ(file("a.cbk"), good);
  EXPECT_TRUE(others("a.cbk").empty());
}

// Bakes big.toml over a.cbk, paused mid-write by the sink's test hook, and sends `signo` once the
// temporary file holds 50 000 bytes. Returns the wait status; `partial` says whether the pause
// was reached.
int Cli::interrupt_bake_mid_write(int signo, bool& partial) {
  std::ofstream(dir_ / "big.toml") << "name = \"big\"\n[weave]\nname = \"plain\"\n"
                                      "[[yarn]]\nname = \"warp\"\n[[yarn]]\nname = \"weft\"\n"
                                      "[bake]\nresolution = 128\n";
  SpawnOptions pause;
  pause.env = {"CLOTHBAKE_TEST_PAUSE_AFTER_BYTES=50000"};
  const pid_t pid =
      spawn(dir_ / "io", prefix({"bake", "@big.toml", "-o", "@a.cbk", "--stages", "feature_maps"}),
            pause);
  partial = false;
  for (int i = 0; i < 1000 && !partial; ++i) {
    for (const auto& name : others("a.cbk"))
      if (fs::file_size(dir_ / name) >= 50000) partial = true;
    if (!partial) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, signo);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

TEST_F(Cli, SigkillMidWriteLeavesThePreviousAsset) {
  ASSERT_EQ(run({"bake", "@fabric.toml", "-o", "@a.cbk", "--stages", "feature_maps"}).code, 0);
  const std::string good = file("a.cbk");
  bool partial = false;
  const int status = interrupt_bake_mid_write(SIGKILL, partial);
  ASSERT_TRUE(partial) << "the bake never paused mid-write";
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(file("a.cbk"), good);
  const Outcome v = run({"validate", "@a.cbk"});
  EXPECT_EQ(v.code, 0) << v.out;
  // SIGKILL cannot be caught, so its temporary file stays; the next bake to that path removes it.
  ASSERT_EQ(others("a.cbk").size(), 1u);
  const Outcome again = run({"bake", "@fabric.toml", "-o", "@a.cbk", "--stages", "feature_maps"});
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_TRUE(others("a.cbk").empty());
  EXPECT_IN("a temporary file left by an interrupted write", again.err);
}

// Ctrl-C (SIGINT) and SIGTERM mid-write: the temporary file is removed, the previous asset stays
// byte for byte, and the process ends by that signal (a shell reports 128 + N).
TEST_F(Cli, SigintAndSigtermMidWriteRemoveTheTemporaryFile) {
  ASSERT_EQ(run({"bake", "@fabric.toml", "-o", "@a.cbk", "--stages", "feature_maps"}).code, 0);
  const std::string good = file("a.cbk");
  for (const int signo : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(signo);
    bool partial = false;
    const int status = interrupt_bake_mid_write(signo, partial);
    ASSERT_TRUE(partial) << "the bake never paused mid-write";
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), signo);
    EXPECT_TRUE(others("a.cbk").empty());
    EXPECT_EQ(file("a.cbk"), good);
  }
}

TEST_F(Cli, DamagedAndForeignAssets) {
  ASSERT_EQ(run({"bake", "@fabric.toml", "-o", "@a.cbk", "--stages", "feature_maps"}).code, 0);
  std::string bytes = file("a.cbk");
  // A flipped payload byte: validate names the section with CBK-E012, exit 3.
  std::string damaged = bytes;
  damaged[damaged.size() - 100] ^= 0x40;
  std::ofstream(dir_ / "damaged.cbk", std::ios::binary) << damaged;
  Outcome r = run({"validate", "@damaged.cbk", "--json"});
  EXPECT_EQ(r.code, 3);
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["valid"], false);
  EXPECT_EQ(doc["findings"][0]["id"], "CBK-E012");
  EXPECT_IN("albedo", doc["findings"][0]["message"].get<std::string>());
  r = run({"export", "@damaged.cbk", "--section", "albedo", "-o", "@x.exr"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("CBK-E012", r.err);
  // Truncated.
  std::ofstream(dir_ / "short.cbk", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  r = run({"validate", "@short.cbk"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("CBK-E002", r.out);
  r = run({"info", "@short.cbk"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("truncated", r.err);
  // A newer major version: the message says which side to rebuild.
  std::string newer = bytes;
  newer[8] = 3;
  std::ofstream(dir_ / "newer.cbk", std::ios::binary) << newer;
  r = run({"info", "@newer.cbk"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("CBK-E003", r.err);
  EXPECT_IN("rebuild the reader", r.err);
  r = run({"validate", "@newer.cbk"});
  EXPECT_EQ(r.code, 3);
  // A flipped header flag bit: the structure holds, the header checksum does not. info (which
  // verifies it) and validate exit 3 with CBK-E004; the damaged payload above still describes.
  std::string flagged = bytes;
  flagged[20] ^= 0x01;
  std::ofstream(dir_ / "flagged.cbk", std::ios::binary) << flagged;
  r = run({"info", "@flagged.cbk"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("CBK-E004", r.err);
  r = run({"validate", "@flagged.cbk"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("CBK-E004", r.out);
  EXPECT_EQ(run({"info", "@damaged.cbk"}).code, 0);
  // Not an asset at all.
  std::ofstream(dir_ / "text.cbk") << std::string(200, 'x');
  r = run({"validate", "@text.cbk"});
  EXPECT_EQ(r.code, 3);
  EXPECT_IN("CBK-E001", r.out);
  // Missing file: an I/O error.
  r = run({"validate", "@missing.cbk"});
  EXPECT_EQ(r.code, 2);
  r = run({"info", "@missing.cbk"});
  EXPECT_EQ(r.code, 2);
}

}  // namespace

namespace {

// Section names of a bake's --json report, counted.
std::map<std::string, int> section_counts(const nlohmann::json& report) {
  std::map<std::string, int> counts;
  for (const auto& s : report["asset"]["sections"])
    ++counts[s["name"].get<std::string>()];
  return counts;
}

const char* kSmallCompressFabric =
    "name = \"compress cli\"\n[weave]\nname = \"twill2/1\"\n"
    "[[yarn]]\nname = \"warp\"\nroughness = 0.3\n[[yarn]]\nname = \"weft\"\nroughness = 0.2\n"
    "[bake]\nresolution = 32\nradiance_dirs = 8\nparallax_dirs = 8\nvisibility_dirs = 8\n"
    "clusters = 4\n";

}  // namespace

TEST_F(Cli, CompressionOptionsDecideWhichTablesAreWritten) {
  std::ofstream(dir_ / "c.toml") << kSmallCompressFabric;
  // Default: compressed tables only; the raw ones are superseded (named in the metadata).
  Outcome r = run({"bake", "@c.toml", "-o", "@default.cbk", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  auto counts = section_counts(nlohmann::json::parse(r.out));
  EXPECT_GT(counts["radiance_compressed"], 0);
  EXPECT_EQ(counts["radiance_tables"], 0);
  r = run({"info", "@default.cbk", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto metadata = nlohmann::json::parse(r.out)["metadata"];
  EXPECT_EQ(metadata["omitted_sections"][0]["artifact"], "section/tables");
  EXPECT_EQ(metadata["parameters"]["compress"]["mode"], "target");
  EXPECT_EQ(metadata["parameters"]["compress"]["keep_raw"], false);
  // The per-texel ASG fit errors are information only: left out by default (the info record keeps
  // their mean and maximum), and every reading command copes with their absence.
  EXPECT_EQ(counts["visibility_asg"], 2);
  EXPECT_EQ(counts["asg_fit_error"], 0);
  EXPECT_EQ(metadata["parameters"]["visibility"]["fit_error_section"], false);
  EXPECT_GT(metadata["parameters"]["visibility"]["max_fit_error"].get<double>(), 0.0);
  EXPECT_EQ(metadata["format_version"], "2.0");
  r = run({"validate", "@default.cbk"});
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  r = run({"verify", "@default.cbk", "--fabric", "@c.toml", "--json"});
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  r = run({"query", "@default.cbk", "visibility", "--texel", "3,4", "--dir", "0,0,1", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["fit_error"].is_null()) << r.out;

  r = run({"bake", "@c.toml", "-o", "@both.cbk", "--keep-raw", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  counts = section_counts(nlohmann::json::parse(r.out));
  EXPECT_GT(counts["radiance_compressed"], 0);
  EXPECT_GT(counts["radiance_tables"], 0);
  EXPECT_EQ(counts["asg_fit_error"], 1);  // --keep-raw keeps them

  r = run({"bake", "@c.toml", "-o", "@raw.cbk", "--no-compress", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  counts = section_counts(nlohmann::json::parse(r.out));
  EXPECT_EQ(counts["radiance_compressed"], 0);
  EXPECT_GT(counts["radiance_tables"], 0);
  EXPECT_EQ(counts["asg_fit_error"], 1);  // an uncompressed bake keeps all raw data

  // --stages without compress: the raw tables, as before compression existed.
  r = run({"bake", "@c.toml", "-o", "@tables.cbk", "--stages", "tables", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  counts = section_counts(nlohmann::json::parse(r.out));
  EXPECT_EQ(counts["radiance_compressed"], 0);
  EXPECT_GT(counts["radiance_tables"], 0);

  // A fixed shape and a target error reach the stage.
  r = run({"bake", "@c.toml", "-o", "@fixed.cbk", "--compress", "1,3", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = run({"info", "@fixed.cbk", "--json"});
  auto compress = nlohmann::json::parse(r.out)["metadata"]["parameters"]["compress"];
  EXPECT_EQ(compress["mode"], "fixed");
  EXPECT_EQ(compress["kinds"][0]["max_rank"], 3);
  r = run({"bake", "@c.toml", "-o", "@target.cbk", "--max-error", "0.05", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = run({"info", "@target.cbk", "--json"});
  compress = nlohmann::json::parse(r.out)["metadata"]["parameters"]["compress"];
  EXPECT_EQ(compress["mode"], "target");
  EXPECT_DOUBLE_EQ(compress["max_error"].get<double>(), 0.05);
  EXPECT_LE(compress["kinds"][0]["relative_rms_error"].get<double>(), 0.05 * 1.0001);
}

TEST_F(Cli, ConflictingCompressionOptionsAreUsageErrors) {
  std::ofstream(dir_ / "c.toml") << kSmallCompressFabric;
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--no-compress", "--keep-raw"}, "--no-compress conflicts with --keep-raw"},
      {{"--no-compress", "--compress", "1,4"}, "--no-compress conflicts with --compress"},
      {{"--no-compress", "--max-error", "0.01"}, "--no-compress conflicts with --max-error"},
      {{"--compress", "1,4", "--max-error", "0.01"}, "--compress conflicts with --max-error"},
      {{"--compress", "4"}, "--compress expects K,R"},
      {{"--compress", "0,4"}, "K must be in [1, 64]"},
      {{"--max-error", "0"}, "--max-error expects a relative RMS error in (0, 1]"},
      {{"--keep-raw", "--stages", "feature_maps"}, "--keep-raw has no effect: --stages"},
  };
  for (const auto& [options, message] : cases) {
    std::vector<std::string> args{"bake", "@c.toml", "-o", "@x.cbk"};
    args.insert(args.end(), options.begin(), options.end());
    const Outcome r = run(args);
    EXPECT_EQ(r.code, 1) << message << "\n" << r.err;
    EXPECT_IN(message, r.err);
    EXPECT_FALSE(fs::exists(dir_ / "x.cbk")) << message;
  }
}

// A mistyped command is a usage error naming it and the closest command; a word near none gets no
// suggestion; an empty command line still asks for one; CLI11's errors have clothbake's style.
TEST_F(Cli, UnknownCommandSuggestsTheClosest) {
  Outcome r = run({"rendr", "scene.toml"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("unknown command 'rendr'; did you mean 'render'?", r.err);
  r = run({"valdiate"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("did you mean 'validate'?", r.err);
  r = run({"xyzzyplugh"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("unknown command 'xyzzyplugh'", r.err);
  EXPECT_EQ(r.err.find("did you mean"), std::string::npos) << r.err;
  r = run({});
  EXPECT_EQ(r.code, 1);
  r = run({"--version"});
  EXPECT_EQ(r.code, 0);
  // CLI11's own refusals speak the same way as clothbake's: prefix, message, where to look.
  r = run({"bake", "--threads", "x"});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("clothbake: error: --threads", 0), 0u) << r.err;
  EXPECT_IN("(clothbake bake --help lists the options)", r.err);
  EXPECT_EQ(r.err.find("Run with --help"), std::string::npos) << r.err;
  // A subcommand's subcommand names its own help, where its options are listed; an option of
  // another report is unknown to this one.
  r = run({"report", "stability", "-o", "r", "--image-size", "8,8"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("(clothbake report stability --help lists the options)", r.err);
  r = run({"report", "plan", "scene.toml", "-o", "r", "--spp", "1,2"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("--spp", r.err);
  EXPECT_IN("(clothbake report plan --help lists the options)", r.err);
}

// bake takes a WIF draft directly (the README's input) and --resolution N for a weave's maps (what
// pattern and report take); with --scene it is a usage error (the plan is made at the fabric's own
// resolution); a scene given to bake is named as one.
TEST_F(Cli, BakesAWifDraftAndTakesAResolution) {
  const std::string wif = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/wif/twill-2-2.wif";
  std::ofstream(dir_ / "c.toml") << kSmallCompressFabric;
  Outcome r = run({"bake", wif, "-o", "@w.cbk", "--resolution", "16", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = run({"info", "@w.cbk", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["fabric_info"]["resolution"], 16) << r.out;
  r = run({"bake", "@c.toml", "-o", "@c16.cbk", "--resolution", "16", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = run({"info", "@c16.cbk", "--json"});
  EXPECT_EQ(nlohmann::json::parse(r.out)["fabric_info"]["resolution"], 16) << r.out;
  r = run({"bake", "@c.toml", "-o", "@x.cbk", "--resolution", "16", "--scene",
           std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/scenes/far-swatch.toml"});
  EXPECT_EQ(r.code, 1);
  EXPECT_IN("cannot be combined with --resolution", r.err);
  r = run(
      {"bake", std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/scenes/room.toml", "-o", "@y.cbk"});
  EXPECT_EQ(r.code, 2);
  EXPECT_IN("is a scene, not a fabric description", r.err);
  EXPECT_FALSE(fs::exists(dir_ / "x.cbk"));
  EXPECT_FALSE(fs::exists(dir_ / "y.cbk"));
}

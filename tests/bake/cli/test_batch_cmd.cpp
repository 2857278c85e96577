// `clothbake batch` end to end on tiny fabrics: bakes equal single bakes; up-to-date fabrics are
// skipped (a touched but unchanged input too), a changed one alone is rebaked; a missing file in
// the list, two fabrics mapped to one output, a broken fabric and a full disk fail with a message
// naming the fabric while the rest are baked, nothing partial is left, the exit code is 2; the
// emitted Slurm array script parses and its tasks, run as Slurm would, give the same bytes.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "tests/support/files.hpp"
#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;
using clothbake::test_support::clothbake_executable;
using clothbake::test_support::run_clothbake;

namespace {

std::string fabric(const std::string& weave, int resolution = 16) {
  return "[weave]\nname = \"" + weave + "\"\n[bake]\nresolution = " + std::to_string(resolution) +
         "\nparallax_dirs = 4\nvisibility_dirs = 4\nradiance_dirs = 6\nclusters = 2\n";
}

using clothbake::test_support::slurp;

class Batch : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake_batch_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "lib");
    std::ofstream(dir_ / "lib" / "plain.toml") << fabric("plain");
    std::ofstream(dir_ / "lib" / "twill.toml") << fabric("twill2/1");
    std::ofstream(dir_ / "lib" / "satin.toml") << fabric("satin5");
  }
  void TearDown() override { fs::remove_all(dir_); }
  nlohmann::json batch(const std::vector<std::string>& extra, int expect = 0) {
    std::vector<std::string> args = {"batch", (dir_ / "lib").string(), "-o",
                                     (dir_ / "out").string(), "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_clothbake(args);
    EXPECT_EQ(r.code, expect) << r.err << r.out;
    return nlohmann::json::parse(r.out.empty() ? "{}" : r.out);
  }
  static std::map<std::string, std::string> statuses(const nlohmann::json& doc) {
    std::map<std::string, std::string> out;
    for (const auto& f : doc["fabrics"])
      out[fs::path(f["fabric"].get<std::string>()).stem().string()] = f["status"];
    return out;
  }
  std::string single_bake(const std::string& name) {
    const fs::path out = dir_ / ("single-" + name + ".cbk");
    const auto r = run_clothbake(
        {"bake", (dir_ / "lib" / (name + ".toml")).string(), "-o", out.string(), "--quiet"});
    EXPECT_EQ(r.code, 0) << r.err;
    return slurp(out);
  }
  bool no_temporary_files(const fs::path& dir) const {
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().find(".tmp-") != std::string::npos) return false;
    return true;
  }
  fs::path dir_;
};

TEST_F(Batch, BakesSkipsUpToDateAndRebakesOnlyWhatChanged) {
  auto doc = batch({"--jobs", "2", "--cache", (dir_ / "cache").string()});
  EXPECT_EQ(doc["baked"], 3);
  for (const std::string name : {"plain", "twill", "satin"})
    EXPECT_EQ(slurp(dir_ / "out" / (name + ".cbk")), single_bake(name)) << name;
  doc = batch({"--jobs", "2"});
  EXPECT_EQ(doc["up_to_date"], 3);
  // Touched, same content: still up to date (the hash confirms).
  fs::last_write_time(dir_ / "lib" / "twill.toml", fs::file_time_type::clock::now());
  EXPECT_EQ(batch({})["up_to_date"], 3);
  // Changed content: that fabric alone is baked again.
  std::ofstream(dir_ / "lib" / "twill.toml") << fabric("twill2/1") << "seed = 7\n";
  const auto s = statuses(batch({}));
  EXPECT_EQ(s.at("twill"), "baked");
  EXPECT_EQ(s.at("plain"), "up-to-date");
  EXPECT_EQ(s.at("satin"), "up-to-date");
  // A deleted output is baked again.
  fs::remove(dir_ / "out" / "plain.cbk");
  EXPECT_EQ(statuses(batch({})).at("plain"), "baked");
}

// --scene: each bake is that fabric's plan for the scene (byte-identical to `bake --scene`); a
// fabric the scene does not use fails alone; a changed scene rebakes the fabrics it plans.
TEST_F(Batch, SceneBakesEachFabricsPlan) {
  const std::string scene_text =
      "[camera]\nposition = [0, 0, 3]\nresolution = [8, 8]\n[[light]]\ntype = "
      "\"directional\"\ndirection = [0.2, 0.1, -1]\n[[object]]\nshape = \"plane\"\nfabric = "
      "\"lib/plain.toml\"\n[[object]]\nshape = \"plane\"\ncenter = [0.6, 0, 0.1]\nsize = "
      "[0.3, 0.3]\nfabric = \"lib/satin.toml\"\n";
  std::ofstream(dir_ / "scene.toml") << scene_text;
  auto s = statuses(batch({"--scene", (dir_ / "scene.toml").string()}, 2));
  EXPECT_EQ(s.at("plain"), "baked");
  EXPECT_EQ(s.at("satin"), "baked");
  EXPECT_EQ(s.at("twill"), "failed");  // not in the scene
  const fs::path single = dir_ / "single-plain-planned.cbk";
  ASSERT_EQ(run_clothbake({"bake", (dir_ / "lib" / "plain.toml").string(), "--scene",
                           (dir_ / "scene.toml").string(), "-o", single.string(), "--quiet"})
                .code,
            0);
  EXPECT_EQ(slurp(dir_ / "out" / "plain.cbk"), slurp(single));
  EXPECT_EQ(statuses(batch({"--scene", (dir_ / "scene.toml").string()}, 2)).at("plain"),
            "up-to-date");
  std::ofstream(dir_ / "scene.toml") << scene_text << "[render]\nmax_error = 0.01\n";
  EXPECT_EQ(statuses(batch({"--scene", (dir_ / "scene.toml").string()}, 2)).at("plain"), "baked");
  // A missing scene is a bad command line for the whole batch, before any bake.
  batch({"--scene", (dir_ / "nope.toml").string()}, 2);
}

TEST_F(Batch, BadEntriesFailAloneWithAMessage) {
  fs::create_directories(dir_ / "other");
  std::ofstream(dir_ / "other" / "plain.toml") << fabric("plain");
  std::ofstream(dir_ / "lib" / "broken.toml") << "[weave]\nname = \"nope\"\n";
  std::ofstream(dir_ / "list.txt") << "# a list\nlib/plain.toml\nother/plain.toml\n"
                                   << "lib/missing.toml\n\nlib/twill.toml\nlib/broken.toml\n";
  const auto r = run_clothbake(
      {"batch", (dir_ / "list.txt").string(), "-o", (dir_ / "out").string(), "--json"});
  EXPECT_EQ(r.code, 2) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  std::map<std::string, nlohmann::json> rows;
  for (const auto& f : doc["fabrics"])
    rows[f["fabric"]] = f;
  const std::string lib = (dir_ / "lib").string(), other = (dir_ / "other").string();
  EXPECT_EQ(rows[lib + "/plain.toml"]["status"], "failed");
  EXPECT_NE(rows[lib + "/plain.toml"]["note"].get<std::string>().find("two fabrics map to"),
            std::string::npos);
  EXPECT_EQ(rows[other + "/plain.toml"]["status"], "failed");
  EXPECT_NE(rows[lib + "/missing.toml"]["note"].get<std::string>().find("file not found"),
            std::string::npos);
  EXPECT_NE(rows[lib + "/broken.toml"]["note"].get<std::string>().find("unknown weave 'nope'"),
            std::string::npos);
  EXPECT_EQ(rows[lib + "/twill.toml"]["status"], "baked");
  EXPECT_TRUE(fs::exists(dir_ / "out" / "twill.cbk"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "plain.cbk"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "broken.cbk"));
  EXPECT_TRUE(no_temporary_files(dir_ / "out"));
}

// Lists that are not regular files are refused at once (a FIFO blocked for ever, /dev/zero read
// 2 GB); a list naming no fabric leaves no OUTDIR; a directory or device in a list is named as what
// it is; a stamp of the wrong JSON types means "bake again" (it was exit 4); a fabric name that is
// not UTF-8 is baked once and then up to date (it failed and was rebaked on every run); control
// bytes in names are escaped in the table.
TEST_F(Batch, HostileListsStampsAndNames) {
  const std::string out = (dir_ / "out").string();
  const fs::path fifo = dir_ / "list.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& list : {fifo.string(), std::string("/dev/zero")}) {
    const auto start = std::chrono::steady_clock::now();
    const auto r = clothbake::test_support::detail::spawn(
        {"/usr/bin/timeout", "20", clothbake_executable(), "batch", list, "-o", out});
    EXPECT_EQ(r.code, 2) << list << ": " << r.err;
    EXPECT_NE(r.err.find("not a regular file"), std::string::npos) << r.err;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5);
    EXPECT_FALSE(fs::exists(out)) << list;
  }
  std::ofstream(dir_ / "empty.txt") << "# nothing here\n\n";
  auto r = run_clothbake({"batch", (dir_ / "empty.txt").string(), "-o", out});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("names no fabric"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));

  std::ofstream(dir_ / "odd.txt") << "lib\n/dev/null\n";
  r = run_clothbake({"batch", (dir_ / "odd.txt").string(), "-o", out, "--json"});
  EXPECT_EQ(r.code, 2) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["fabrics"].size(), 2u);
  EXPECT_NE(doc["fabrics"][0]["note"].get<std::string>().find("is a directory"), std::string::npos)
      << doc["fabrics"][0]["note"];
  EXPECT_NE(doc["fabrics"][1]["note"].get<std::string>().find("not a regular file"),
            std::string::npos)
      << doc["fabrics"][1]["note"];

  // Names: Latin-1 "café" (not UTF-8) and an ESC sequence.
  fs::create_directories(dir_ / "names");
  const std::string latin1 = "caf\xe9", escape = "red\x1b[31m";
  std::ofstream(dir_ / "names" / (latin1 + ".toml")) << fabric("plain");
  std::ofstream(dir_ / "names" / (escape + ".toml")) << fabric("plain");
  const std::vector<std::string> args = {"batch", (dir_ / "names").string(), "-o", out};
  r = run_clothbake(args);
  EXPECT_EQ(r.code, 0) << r.err << r.out;
  EXPECT_TRUE(fs::exists(dir_ / "out" / (latin1 + ".cbk")));
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("red\\x1B[31m"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("caf\\xE9"), std::string::npos) << r.out;
  r = run_clothbake({"batch", (dir_ / "names").string(), "-o", out, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  const nlohmann::json again = nlohmann::json::parse(r.out);
  for (const auto& f : again["fabrics"])
    EXPECT_EQ(f["status"], "up-to-date") << f;

  // Stamps of the wrong types: baked again, not an internal error.
  const fs::path stamp = dir_ / "out" / ".clothbake-batch" / (latin1 + ".stamp.json");
  for (const std::string& text :
       {std::string(R"({"tool": 5, "output": {"size": "x"}, "inputs": {"path": 1}})"),
        std::string(R"([1, 2, 3])"), std::string("{\"tool\": ")}) {
    std::ofstream(stamp, std::ios::trunc) << text;
    r = run_clothbake({"batch", (dir_ / "names").string(), "-o", out, "--json"});
    EXPECT_EQ(r.code, 0) << text << ": " << r.err;
    bool rebaked = false;
    const nlohmann::json rows = nlohmann::json::parse(r.out);
    for (const auto& f : rows["fabrics"])
      rebaked |=
          f["fabric"].get<std::string>().find("caf") != std::string::npos && f["status"] == "baked";
    EXPECT_TRUE(rebaked) << text << ": " << r.out;
  }
}

// A file size limit (RLIMIT_FSIZE, as a full disk: writes fail) that the small assets fit under and
// the big one does not: the big one fails with the writer's message, the rest are baked, nothing
// partial at any output.
TEST_F(Batch, FullDiskFailsOneFabricAndLeavesNothingPartial) {
  std::ofstream(dir_ / "lib" / "big.toml") << fabric("twill2/1", 128);
  const std::string small = single_bake("plain");
  const uint64_t limit_blocks = (small.size() * 4) / 512;  // dash: ulimit -f counts 512 B blocks
  const std::string command = "ulimit -f " + std::to_string(limit_blocks) +
                              "; trap '' XFSZ; exec '" + clothbake_executable() + "' batch '" +
                              (dir_ / "lib").string() + "' -o '" + (dir_ / "out").string() +
                              "' --json";
  const auto limited = clothbake::test_support::detail::spawn({"/bin/sh", "-c", command});
  EXPECT_EQ(limited.code, 2) << limited.err;
  const auto doc = nlohmann::json::parse(limited.out);
  const auto s = statuses(doc);
  EXPECT_EQ(s.at("big"), "failed");
  EXPECT_EQ(s.at("plain"), "baked");
  EXPECT_EQ(s.at("twill"), "baked");
  for (const auto& f : doc["fabrics"]) {
    if (f["status"] == "failed") {
      EXPECT_NE(f["note"].get<std::string>().find("big.cbk"), std::string::npos) << f["note"];
    }
  }
  EXPECT_FALSE(fs::exists(dir_ / "out" / "big.cbk"));
  EXPECT_TRUE(no_temporary_files(dir_ / "out"));
}

TEST_F(Batch, MemoryLimitStillBakesEverything) {
  // A limit below any bake's peak: one bake at a time, all baked.
  const auto doc = batch({"--jobs", "2", "--max-memory", "1M"});
  EXPECT_EQ(doc["baked"], 3);
}

// --jobs 0: one bake per core (as --threads 0 is all cores); outside [0, 1024] a usage error.
TEST_F(Batch, JobsZeroIsOnePerCore) {
  const auto doc = batch({"--jobs", "0"});
  EXPECT_EQ(doc["baked"], 3);
  EXPECT_EQ(doc["jobs"].get<int>(), std::max(1, int(std::thread::hardware_concurrency())));
  const auto bad = run_clothbake(
      {"batch", (dir_ / "lib").string(), "-o", (dir_ / "out2").string(), "--jobs", "-1"});
  EXPECT_EQ(bad.code, 1) << bad.err;
  EXPECT_NE(bad.err.find("--jobs"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "out2"));
}

// On a terminal a batch says how many it bakes and prints a line as each bake ends (stderr); the
// table on stdout is the same as on a pipe, where stderr stays empty.
TEST_F(Batch, ALineAsEachBakeEndsOnATerminal) {
  const auto tty = clothbake::test_support::run_clothbake_on_terminal(
      {"batch", (dir_ / "lib").string(), "-o", (dir_ / "out").string()});
  ASSERT_EQ(tty.code, 0) << tty.err;
  EXPECT_NE(tty.err.find("batch: baking 3 of 3 fabrics"), std::string::npos) << tty.err;
  for (const char* row : {"[1/3] ", "[2/3] ", "[3/3] "})
    EXPECT_NE(tty.err.find(row), std::string::npos) << tty.err;
  EXPECT_NE(tty.err.find(": baked in "), std::string::npos) << tty.err;
  EXPECT_NE(tty.out.find("3 baked, 0 up to date, 0 failed"), std::string::npos) << tty.out;
  const auto pipe =
      run_clothbake({"batch", (dir_ / "lib").string(), "-o", (dir_ / "out2").string()});
  ASSERT_EQ(pipe.code, 0) << pipe.err;
  EXPECT_EQ(pipe.err, "");
  EXPECT_NE(pipe.out.find("3 baked, 0 up to date, 0 failed"), std::string::npos) << pipe.out;
}

// The emitted script: bash parses it, its directives are those documented, and running each array
// task as Slurm would (SLURM_ARRAY_TASK_ID set) gives assets byte-identical to local bakes.
TEST_F(Batch, EmittedSlurmArrayRunsTheSameBakes) {
  const auto r = run_clothbake({"batch", (dir_ / "lib").string(), "-o", (dir_ / "out").string(),
                                "--emit", "slurm", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["tasks"], 3);
  const std::string script = doc["script"];
  const std::string text = slurp(script);
  EXPECT_NE(text.find("#SBATCH --array=0-2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("#SBATCH --mem="), std::string::npos);
  EXPECT_NE(text.find("#SBATCH --cpus-per-task="), std::string::npos);
  EXPECT_NE(text.find("#SBATCH --output="), std::string::npos);
  ASSERT_EQ(std::system(("bash -n '" + script + "'").c_str()), 0);
  for (int task = 0; task < 3; ++task) {
    const std::string run = "SLURM_ARRAY_TASK_ID=" + std::to_string(task) +
                            " SLURM_CPUS_PER_TASK=1 bash '" + script + "'";
    ASSERT_EQ(std::system(run.c_str()), 0) << task;
  }
  for (const std::string name : {"plain", "twill", "satin"})
    EXPECT_EQ(slurp(dir_ / "out" / (name + ".cbk")), single_bake(name)) << name;
}

}  // namespace

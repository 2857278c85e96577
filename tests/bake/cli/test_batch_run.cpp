// The batch engine (bake/cli/batch_run.hpp) called directly, without baking: which fabrics a
// folder or a list names and where their outputs go, the failures it reports as jobs rather than
// errors, the stamp check of fabrics never baked, and the Slurm array of the pending ones.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "bake/cli/batch_run.hpp"
#include "common/error.hpp"
#include "tests/support/files.hpp"
#include "tests/support/scratch_dir.hpp"

namespace fs = std::filesystem;

namespace clothbake::cli {
namespace {

using clothbake::test_support::slurp;

class BatchRunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_ / "lib");
    for (const char* name : {"b.toml", "a.toml"})
      std::ofstream(dir_ / "lib" / name) << "[weave]\nname = \"plain\"\n";
    std::ofstream(dir_ / "lib" / "notes.txt") << "not a fabric\n";
  }
  BatchOptions options(const fs::path& source) const {
    BatchOptions o;
    o.source = source.string();
    o.output_dir = (dir_ / "out").string();
    o.cache = (dir_ / "cache").string();  // not $CLOTHBAKE_CACHE of whoever runs the tests
    return o;
  }
  test_support::ScratchDir scratch_;  // removed when the test ends
  const fs::path dir_ = scratch_.path();
};

TEST_F(BatchRunTest, AFolderGivesItsFabricsSortedWithOneOutputEach) {
  const auto jobs = list_batch_jobs(options(dir_ / "lib"));
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0].name, "a");
  EXPECT_EQ(jobs[1].name, "b");
  EXPECT_EQ(jobs[0].output, (dir_ / "out" / "a.cbk").string());
  for (const auto& j : jobs)
    EXPECT_EQ(j.status, "pending") << j.note;
}

TEST_F(BatchRunTest, AListResolvesAgainstItsFolderAndReportsBadEntriesAsFailedJobs) {
  fs::create_directories(dir_ / "lists");
  std::ofstream(dir_ / "lists" / "fabrics.txt")
      << "# a comment\n\n  ../lib/a.toml  \n"
      << (dir_ / "lib" / "b.toml").string() << "\nmissing.toml\n../lib\n";
  const auto jobs = list_batch_jobs(options(dir_ / "lists" / "fabrics.txt"));
  ASSERT_EQ(jobs.size(), 4u);
  EXPECT_EQ(fs::path(jobs[0].fabric), dir_ / "lists" / ".." / "lib" / "a.toml");
  EXPECT_EQ(jobs[0].status, "pending") << jobs[0].note;
  EXPECT_EQ(jobs[1].status, "pending") << jobs[1].note;
  EXPECT_EQ(jobs[2].status, "failed");
  EXPECT_NE(jobs[2].note.find("missing.toml"), std::string::npos) << jobs[2].note;
  EXPECT_EQ(jobs[3].status, "failed");  // a folder, named as one
  EXPECT_NE(jobs[3].note.find("directory"), std::string::npos) << jobs[3].note;
}

TEST_F(BatchRunTest, TwoFabricsOfOneStemBothFailNamingEachOther) {
  fs::create_directories(dir_ / "other");
  std::ofstream(dir_ / "other" / "a.toml") << "[weave]\nname = \"twill2/1\"\n";
  std::ofstream(dir_ / "list.txt") << "lib/a.toml\nother/a.toml\nlib/b.toml\n";
  const auto jobs = list_batch_jobs(options(dir_ / "list.txt"));
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].status, "failed");
  EXPECT_EQ(jobs[1].status, "failed");
  EXPECT_NE(jobs[0].note.find("other/a.toml"), std::string::npos) << jobs[0].note;
  EXPECT_NE(jobs[1].note.find("lib/a.toml"), std::string::npos) << jobs[1].note;
  EXPECT_EQ(jobs[2].status, "pending");
}

TEST_F(BatchRunTest, ASourceWithoutFabricsIsAnInputError) {
  fs::create_directories(dir_ / "empty");
  try {
    (void)list_batch_jobs(options(dir_ / "empty"));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("names no fabric"), std::string::npos) << e.what();
  }
}

TEST_F(BatchRunTest, FabricsNeverBakedStayPendingWithTheUnknownPeak) {
  const BatchOptions o = options(dir_ / "lib");
  auto jobs = list_batch_jobs(o);
  EXPECT_EQ(check_batch_stamps(o, jobs), kUnknownPeakBytes);
  EXPECT_TRUE(fs::is_directory(dir_ / "out" / ".clothbake-batch"));
  for (const auto& j : jobs) {
    EXPECT_EQ(j.status, "pending");
    EXPECT_EQ(j.note, "never baked");
  }
}

TEST_F(BatchRunTest, TheSlurmArrayHasOneTaskPerPendingFabric) {
  BatchOptions o = options(dir_ / "lib");
  o.scene = (dir_ / "it's a scene.toml").string();  // quoted for the shell
  auto jobs = list_batch_jobs(o);
  jobs.push_back(jobs[0]);
  jobs.back().status = "failed";  // not a task
  fs::create_directories(o.output_dir);
  const SlurmScript s = write_slurm_script(o, jobs, uint64_t(1) << 30);
  EXPECT_EQ(s.tasks, 2u);
  EXPECT_EQ(s.mem_mb, 1280u + 64u);  // 1 GiB + 25 % + 64 MiB
  const std::string list = slurp(s.list);
  EXPECT_EQ(list, fs::absolute(jobs[0].fabric).string() + "\n" +
                      fs::absolute(jobs[1].fabric).string() + "\n");
  const std::string script = slurp(s.script);
  EXPECT_NE(script.find("#SBATCH --array=0-1\n"), std::string::npos) << script;
  auto quoted = [](const std::string& text) {  // the shell's single quotes, ' as '\''
    std::string out = "'";
    for (char c : text)
      out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
  };
  EXPECT_NE(script.find("--scene " + quoted(o.scene)), std::string::npos) << script;
  EXPECT_NE(script.find("--cache " + quoted(o.cache)), std::string::npos) << script;
  struct stat st {};
  ASSERT_EQ(::stat(s.script.c_str(), &st), 0);
  EXPECT_TRUE(st.st_mode & S_IXUSR);
}

// The scheduler with a stand-in for clothbake: a shell script that "bakes" (writes the output and
// a report naming the fabric as input) or fails with a message, as the real bake does.
TEST_F(BatchRunTest, TheSchedulerBakesWhatIsPendingAndReportsEachEnd) {
  std::ofstream(dir_ / "lib" / "fail.toml") << "[weave]\nname = \"plain\"\n";
  const fs::path stand_in = dir_ / "stand-in.sh";
  std::ofstream(stand_in)
      << "#!/bin/sh\n"
         "# bake FABRIC -o OUTPUT --quiet --threads T --report REPORT ...\n"
         "case \"$2\" in *fail.toml) echo \"clothbake: cannot bake $2\" >&2; exit 3;; esac\n"
         "printf 'asset' > \"$4\"\n"
         "printf '{\"total\": {\"peak_rss_bytes\": 1000, \"wall_seconds\": 0.5}, "
         "\"asset\": {\"size_bytes\": 5}, \"inputs\": [{\"role\": \"fabric\", \"path\": "
         "\"%s\", \"xxh64\": \"0\"}]}' \"$2\" > \"$9\"\n";
  fs::permissions(stand_in, fs::perms::owner_all);
  BatchOptions o = options(dir_ / "lib");
  o.executable = stand_in.string();
  o.jobs = 2;
  auto jobs = list_batch_jobs(o);
  ASSERT_EQ(jobs.size(), 3u);  // a, b, fail
  EXPECT_EQ(check_batch_stamps(o, jobs), kUnknownPeakBytes);
  std::size_t started = 0;
  std::vector<std::string> ended;
  const cli::BatchRun run = run_batch(
      o, jobs, uint64_t(1) << 40, kUnknownPeakBytes,
      [&](std::size_t to_bake, int at_once) {
        started = to_bake;
        EXPECT_EQ(at_once, 2);
      },
      [&](const BatchJob& j, std::size_t count, std::size_t to_bake) {
        ended.push_back(j.name);
        EXPECT_EQ(count, ended.size());
        EXPECT_EQ(to_bake, 3u);
      });
  EXPECT_EQ(started, 3u);
  EXPECT_EQ(ended.size(), 3u);
  EXPECT_EQ(run.at_once, 2);
  for (const char* name : {"a", "b"}) {
    const BatchJob& j = jobs[name[0] == 'a' ? 0 : 1];
    EXPECT_EQ(j.status, "baked") << name << ": " << j.note;
    EXPECT_EQ(j.peak, 1000u);
    EXPECT_EQ(j.size, 5u);
    EXPECT_EQ(slurp(j.output), "asset");
  }
  EXPECT_EQ(jobs[2].status, "failed");
  EXPECT_EQ(jobs[2].note, "cannot bake " + jobs[2].fabric);  // the log's last line, unprefixed
  // The stamps written for the baked ones hold: the next check finds them up to date, with the
  // measured peak as the estimate for the rest; the failed one bakes again.
  auto again = list_batch_jobs(o);
  EXPECT_EQ(check_batch_stamps(o, again), 1000u);
  EXPECT_EQ(again[0].status, "up-to-date") << again[0].note;
  EXPECT_EQ(again[1].status, "up-to-date") << again[1].note;
  EXPECT_EQ(again[2].status, "pending");
}

}  // namespace
}  // namespace clothbake::cli

// common/child_process.hpp: forked and spawned children, waiting with a time limit and for any
// child, and wait statuses in words.
#include "common/child_process.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>

#include "tests/support/files.hpp"
#include "tests/support/scratch_dir.hpp"

namespace clothbake {
namespace {

using test_support::ScratchDir;

TEST(ChildProcess, ForkedChildExitCodeIsReported) {
  const ChildStart child = start_child([] { return 3; });
  ASSERT_TRUE(child.ok()) << child.error;
  const ChildWait w = wait_child(child.pid, 30);
  ASSERT_TRUE(w.ended);
  EXPECT_FALSE(w.timed_out);
  EXPECT_EQ(w.error, 0);
  EXPECT_FALSE(child_succeeded(w.status));
  EXPECT_EQ(child_signal(w.status), 0);
  EXPECT_EQ(describe_wait_status(w.status), "exit code 3");
}

TEST(ChildProcess, ForkedChildThatSucceeds) {
  const ChildStart child = start_child([] { return 0; });
  ASSERT_TRUE(child.ok());
  const ChildWait w = wait_child(child.pid, 30);
  ASSERT_TRUE(w.ended);
  EXPECT_TRUE(child_succeeded(w.status));
  EXPECT_EQ(describe_wait_status(w.status), "exit code 0");
}

TEST(ChildProcess, ExceptionInTheChildIsItsExitCode) {
  const ChildStart child = start_child([]() -> int { throw std::runtime_error("no"); });
  ASSERT_TRUE(child.ok());
  const ChildWait w = wait_child(child.pid, 30);
  ASSERT_TRUE(w.ended);
  EXPECT_EQ(describe_wait_status(w.status), "exit code " + std::to_string(kChildBodyThrewExitCode));
}

TEST(ChildProcess, ChildPastTheTimeoutIsKilled) {
  const auto t0 = std::chrono::steady_clock::now();
  const ChildStart child = start_child([] {
    std::this_thread::sleep_for(std::chrono::seconds(30));
    return 0;
  });
  ASSERT_TRUE(child.ok());
  const ChildWait w = wait_child(child.pid, 0.2);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(w.timed_out);
  EXPECT_FALSE(w.ended);
  EXPECT_EQ(child_signal(w.status), 9);
  EXPECT_EQ(describe_wait_status(w.status), "killed by signal 9");
  EXPECT_GE(seconds, 0.2);
  EXPECT_LT(seconds, 10.0);
  // Reaped: it is no longer a child to wait for.
  EXPECT_EQ(wait_child(child.pid, 1).error, ECHILD);
}

TEST(ChildProcess, SpawnedProgramOutputsLandInTheFiles) {
  ScratchDir dir;
  const std::string out = dir / "out.txt", err = dir / "err.log";
  std::ofstream(err) << "an older, longer log that must be truncated\n";
  const ChildStart child =
      spawn_program("/bin/sh", {"-c", "echo to-stdout; echo to-stderr >&2; exit 4"}, out, err);
  ASSERT_TRUE(child.ok()) << child.error;
  const ChildWait w = wait_child(child.pid, 30);
  ASSERT_TRUE(w.ended);
  EXPECT_EQ(describe_wait_status(w.status), "exit code 4");
  EXPECT_EQ(test_support::slurp(out), "to-stdout\n");
  EXPECT_EQ(test_support::slurp(err), "to-stderr\n");
}

TEST(ChildProcess, SpawnOfAMissingProgramFails) {
  const ChildStart child = spawn_program("/nonexistent/clothbake", {}, "/dev/null", "/dev/null");
  EXPECT_FALSE(child.ok());
  EXPECT_EQ(child.pid, -1);
  EXPECT_EQ(child.error, ENOENT);
}

TEST(ChildProcess, WaitAnyReturnsEachChildOnce) {
  std::map<pid_t, int> expected;  // pid -> exit code
  for (int code : {0, 1, 2}) {
    const ChildStart child = start_child([code] {
      std::this_thread::sleep_for(std::chrono::milliseconds(30 * (3 - code)));
      return code;
    });
    ASSERT_TRUE(child.ok());
    expected[child.pid] = code;
  }
  const ChildStart spawned = spawn_program("/bin/sh", {"-c", "exit 5"}, "", "");
  ASSERT_TRUE(spawned.ok());
  expected[spawned.pid] = 5;
  std::set<pid_t> seen;
  for (std::size_t k = 0; k < expected.size(); ++k) {
    const ChildEnd end = wait_any_child();
    ASSERT_GT(end.pid, 0) << end.error;
    ASSERT_TRUE(expected.count(end.pid)) << end.pid;
    EXPECT_TRUE(seen.insert(end.pid).second) << "returned twice: " << end.pid;
    EXPECT_EQ(describe_wait_status(end.status), "exit code " + std::to_string(expected[end.pid]));
  }
  const ChildEnd none = wait_any_child();
  EXPECT_EQ(none.pid, -1);
  EXPECT_EQ(none.error, ECHILD);
}

}  // namespace
}  // namespace clothbake

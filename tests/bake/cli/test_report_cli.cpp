// `clothbake report` through the executable: the exit codes of its usage and output errors (the
// reports themselves are tested in process: tests/bake/reports).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;

TEST(ReportCli, UsageAndOutputErrors) {
  const fs::path dir =
      fs::temp_directory_path() / ("clothbake_report_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // An argument stability does not take, and plan without its scene: usage errors, nothing written.
  auto run = clothbake::test_support::run_clothbake(
      {"report", "stability", "fabric.toml", "-o", (dir / "r").string()});
  EXPECT_EQ(run.code, 1) << run.err;
  EXPECT_FALSE(fs::exists(dir / "r"));
  run = clothbake::test_support::run_clothbake({"report", "plan", "-o", (dir / "r").string()});
  EXPECT_EQ(run.code, 1) << run.err;
  // An output that is a file: exit 2.
  std::ofstream(dir / "file") << "x";
  run = clothbake::test_support::run_clothbake(
      {"report", "stability", "-o", (dir / "file").string()});
  EXPECT_EQ(run.code, 2) << run.err;
  // A library's refusal of an option value reads like the parser's: it names where the options
  // are listed.
  run = clothbake::test_support::run_clothbake(
      {"report", "error-time", "scene.toml", "-o", (dir / "e").string(), "--methods", "fast"});
  EXPECT_EQ(run.code, 1) << run.err;
  EXPECT_NE(run.err.find("--methods: unknown method 'fast'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("(clothbake report error-time --help lists the options)"),
            std::string::npos)
      << run.err;
  fs::remove_all(dir);
}

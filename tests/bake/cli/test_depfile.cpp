// Depfile escaping (golden strings, and GNU Make reading the escaped names back) and
// `clothbake bake --depfile` / restat end to end.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bake/cli/depfile.hpp"
#include "common/error.hpp"
#include "tests/support/files.hpp"
#include "tests/support/run_cli.hpp"

namespace fs = std::filesystem;
using namespace clothbake;
using clothbake::test_support::run_clothbake;

namespace {

fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("clothbake_depfile_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

using clothbake::test_support::slurp;

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

int64_t mtime_ns(const fs::path& p) {
  struct stat st {};
  ::stat(p.c_str(), &st);
  return int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
}

const char* kTinyFabric = R"(name = "tiny"
[weave]
name = "twill2/1"
[bake]
resolution = 16
parallax_dirs = 4
visibility_dirs = 4
radiance_dirs = 6
clusters = 2
)";

}  // namespace

TEST(Depfile, EscapesAsNinjaAndMakeExpect) {
  EXPECT_EQ(cli::escape_depfile_path("plain/a.png"), "plain/a.png");
  EXPECT_EQ(cli::escape_depfile_path("a b.png"), "a\\ b.png");
  EXPECT_EQ(cli::escape_depfile_path("c#d"), "c\\#d");
  EXPECT_EQ(cli::escape_depfile_path("e$f"), "e$$f");
  EXPECT_EQ(cli::escape_depfile_path("tab\there"), "tab\\\there");
  // A backslash before a space is doubled so that it stays a literal backslash.
  EXPECT_EQ(cli::escape_depfile_path("x\\ y"), "x\\\\\\ y");
  EXPECT_EQ(cli::escape_depfile_path("win\\path"), "win\\path");
  EXPECT_THROW(cli::escape_depfile_path("bad\nname"), Error);
  // ':' is "\:" for both; at the end of a path or after a backslash they read it differently.
  EXPECT_EQ(cli::escape_depfile_path("a:b"), "a\\:b");
  EXPECT_EQ(cli::escape_depfile_path("c: d"), "c\\:\\ d");
  EXPECT_THROW(cli::escape_depfile_path("ends:"), Error);
  EXPECT_THROW(cli::escape_depfile_path("x\\:y"), Error);
}

TEST(Depfile, TextListsEachDependencyOnceWithPhonyRules) {
  EXPECT_EQ(cli::depfile_text("out.cbk", {"f.toml", "a b.png", "f.toml"}),
            "out.cbk: \\\n  f.toml \\\n  a\\ b.png\n\nf.toml:\n\na\\ b.png:\n");
}

// GNU Make reads the escaped names back as the files they name: touching the file with a space,
// a '#' or a '$' in its name makes the target out of date; deleting one is not an error.
TEST(Depfile, GnuMakeReadsEscapedNames) {
  if (std::system("command -v make >/dev/null 2>&1") != 0) GTEST_SKIP() << "no make";
  const fs::path dir = fresh_dir("make");
  const std::vector<std::string> deps = {"a b.txt", "c#d.txt", "e$f.txt", "g:h.txt", "i: j.txt"};
  const auto past = fs::file_time_type::clock::now() - std::chrono::seconds(1000);
  for (const auto& d : deps) {
    write(dir / d, "x");
    fs::last_write_time(dir / d, past);
  }
  write(dir / "out.d", cli::depfile_text("out", deps));
  write(dir / "Makefile", "out:\n\ttouch out\n-include out.d\n");
  const std::string make = "cd '" + dir.string() + "' && make -s";
  ASSERT_EQ(std::system((make + " >/dev/null").c_str()), 0);
  EXPECT_EQ(std::system((make + " -q out").c_str()), 0) << "up to date after the build";
  for (const auto& d : deps) {
    const auto now = fs::file_time_type::clock::now();
    fs::last_write_time(dir / "out", now - std::chrono::seconds(100));
    fs::last_write_time(dir / d, now - std::chrono::seconds(50));
    EXPECT_NE(std::system((make + " -q out").c_str()), 0) << d << " is newer: must rebuild";
    ASSERT_EQ(std::system((make + " >/dev/null").c_str()), 0);
    EXPECT_EQ(std::system((make + " -q out").c_str()), 0);
  }
  fs::remove(dir / deps[0]);
  EXPECT_EQ(std::system((make + " >/dev/null").c_str()), 0) << "a deleted dependency is no error";
  fs::remove_all(dir);
}

// Ninja 1.11 reads the same names back (`ninja -t deps` lists what it recorded from the depfile).
// A ':' in a path used to make GNU Make refuse the whole depfile ("target pattern contains no
// '%'"), even under -include.
TEST(Depfile, NinjaReadsEscapedNames) {
  if (std::system("command -v ninja >/dev/null 2>&1") != 0) GTEST_SKIP() << "no ninja";
  const fs::path dir = fresh_dir("ninja");
  const std::vector<std::string> deps = {"a b.txt", "c#d.txt", "e$f.txt", "g:h.txt", "i: j.txt"};
  for (const auto& d : deps)
    write(dir / d, "x");
  write(dir / "out.d.src", cli::depfile_text("out", deps));
  write(dir / "build.ninja",
        "rule gen\n  command = cp out.d.src out.d && touch out\n  depfile = out.d\n"
        "  deps = gcc\nbuild out: gen\n");
  const std::string ninja = "cd '" + dir.string() + "' && ninja";
  ASSERT_EQ(std::system((ninja + " >/dev/null").c_str()), 0);
  const test_support::CliRun listed =
      test_support::detail::spawn({"/bin/sh", "-c", ninja + " -t deps"});
  for (const auto& d : deps)
    EXPECT_NE(listed.out.find("    " + d + "\n"), std::string::npos) << d << " in:\n" << listed.out;
  EXPECT_EQ(std::system((ninja + " -n | grep -q 'no work to do'").c_str()), 0);
  fs::last_write_time(dir / deps[3], fs::file_time_type::clock::now() + std::chrono::seconds(5));
  EXPECT_NE(std::system((ninja + " -n | grep -q 'no work to do'").c_str()), 0)
      << "g:h.txt is newer: must rebuild";
  fs::remove_all(dir);
}

// A bake whose depfile cannot name a path (a line break in the fabric's name) or whose --json
// report cannot reach stdout fails before the asset is renamed into place: no new asset, and an
// existing one kept byte for byte (both used to leave the asset of a failed command).
TEST(BakeDepfile, FailedDepfileOrStdoutLeavesNoAsset) {
  const fs::path dir = fresh_dir("leftover");
  write(dir / "a\nb.toml", kTinyFabric);
  const fs::path out = dir / "o.cbk", dep = dir / "o.d";
  auto r = run_clothbake({"bake", (dir / "a\nb.toml").string(), "-o", out.string(), "--depfile",
                          dep.string(), "--quiet"});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("line break"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dep));
  write(dir / "f.toml", kTinyFabric);
  r = test_support::run_clothbake_line("bake '" + (dir / "f.toml").string() + "' -o '" +
                                       out.string() + "' --json --quiet > /dev/full");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("cannot write to standard output"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // An existing output is kept as it was.
  ASSERT_EQ(run_clothbake({"bake", (dir / "f.toml").string(), "-o", out.string(), "--quiet"}).code,
            0);
  const std::string before = slurp(out);
  std::string changed = kTinyFabric;
  changed.replace(changed.find("tiny"), 4, "tinier");
  write(dir / "f.toml", changed);
  r = test_support::run_clothbake_line("bake '" + (dir / "f.toml").string() + "' -o '" +
                                       out.string() + "' --json --quiet > /dev/full");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(slurp(out), before);
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  fs::remove_all(dir);
}

TEST(BakeDepfile, NamesEveryFileReadAndRestatKeepsTheFile) {
  const fs::path dir = fresh_dir("bake");
  write(dir / "tiny fabric.toml", kTinyFabric);
  const fs::path out = dir / "out #1.cbk", dep = dir / "out.d";
  auto r = run_clothbake({"bake", (dir / "tiny fabric.toml").string(), "-o", out.string(),
                          "--depfile", dep.string(), "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string text = slurp(dep);
  EXPECT_EQ(text.rfind(cli::escape_depfile_path(out.string()) + ":", 0), 0u) << text;
  EXPECT_NE(text.find(cli::escape_depfile_path((dir / "tiny fabric.toml").string())),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(cli::escape_depfile_path(
                fs::canonical(test_support::clothbake_executable()).string())),
            std::string::npos)
      << text;

  // Same inputs: same bytes, so the file and its mtime stay; the report says so.
  const std::string bytes = slurp(out);
  fs::last_write_time(out, fs::last_write_time(out) - std::chrono::hours(1));
  const int64_t before = mtime_ns(out);
  r = run_clothbake({"bake", (dir / "tiny fabric.toml").string(), "-o", out.string(), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"unchanged\": true"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("up to date"), std::string::npos) << r.err;
  EXPECT_EQ(mtime_ns(out), before);
  EXPECT_EQ(slurp(out), bytes);

  // A change that alters the bytes rewrites the file.
  std::string changed = kTinyFabric;
  changed.replace(changed.find("tiny"), 4, "tinier");
  write(dir / "tiny fabric.toml", changed);
  r = run_clothbake({"bake", (dir / "tiny fabric.toml").string(), "-o", out.string(), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"unchanged\": false"), std::string::npos);
  EXPECT_NE(mtime_ns(out), before);
  EXPECT_NE(slurp(out), bytes);
  fs::remove_all(dir);
}

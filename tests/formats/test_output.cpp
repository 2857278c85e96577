// Atomic asset files: bad output paths, refusing to overwrite non-assets, simulated disk-full and
// short writes (fault-injecting sink and RLIMIT_FSIZE in a child), SIGKILL, SIGTERM and SIGINT
// mid-write, and the clean-up of stale temporaries. In every failure the previous file at the
// output path is intact and no partial file is left (after SIGKILL: until the next write).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "common/error.hpp"
#include "common/temp_registry.hpp"
#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/writer/asset_writer.hpp"
#include "formats/writer/atomic_file.hpp"
#include "tests/formats/test_fabric.hpp"
#include "tests/support/fabric_asset_sections.hpp"
#include "tests/support/input_error.hpp"

namespace {

using namespace clothbake;
namespace fs = std::filesystem;

class Output : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake-output-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir_, ec);
  }
  static std::vector<formats::Section> sections(int n, const std::string& name) {
    const Fabric fabric = test_support::make_test_fabric(n, name);
    auto s = test_support::fabric_asset_sections(fabric);
    s.push_back(formats::make_metadata_section({{"fabric", name}}));
    return s;
  }
  static std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  // Files in the directory other than `keep`.
  std::vector<std::string> others(const std::string& keep) const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_))
      if (e.path().filename() != keep) names.push_back(e.path().filename().string());
    return names;
  }
  static std::string error_of(const std::function<void()>& f) {
    return test_support::input_error_of(f);
  }
  fs::path dir_;
};

TEST_F(Output, WritesAReadableAssetAndReplacesAnOlderOne) {
  const fs::path out = dir_ / "a.cbk";
  formats::write_asset_file(out, sections(4, "first"), {});
  const std::string first = read(out);
  formats::write_asset_file(out, sections(8, "second"), {});
  const std::string second = read(out);
  EXPECT_NE(first, second);
  reader::Asset asset;
  EXPECT_TRUE(asset.open_file(out.c_str()).ok());
  EXPECT_TRUE(others("a.cbk").empty());
  // Permissions follow the umask, not mkstemp's 0600.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  EXPECT_EQ(uint32_t(fs::status(out).permissions()) & 0777u, 0666u & ~uint32_t(mask));
}

TEST_F(Output, RefusesADirectory) {
  const std::string message =
      error_of([&] { formats::write_asset_file(dir_, sections(4, "x"), {}); });
  EXPECT_NE(message.find("is a directory"), std::string::npos) << message;
}

TEST_F(Output, RefusesAMissingDirectory) {
  const fs::path out = dir_ / "missing" / "a.cbk";
  const std::string message =
      error_of([&] { formats::write_asset_file(out, sections(4, "x"), {}); });
  EXPECT_NE(message.find("does not exist"), std::string::npos) << message;
}

// Text outputs (reports, depfiles, fit-sheen's header): replaced whole, no temporary left, and the
// failing path named.
TEST_F(Output, TextReplacesAnyRegularFileAndNamesTheFailingPath) {
  const fs::path target = dir_ / "table.hpp";
  formats::write_text_atomically(target, "first\n");
  formats::write_text_atomically(target, "second\n");
  EXPECT_EQ(read(target), "second\n");
  EXPECT_TRUE(others("table.hpp").empty());
  const fs::path missing = dir_ / "no-such-dir" / "table.hpp";
  const std::string message = error_of([&] { formats::write_text_atomically(missing, "x"); });
  EXPECT_NE(message.find(missing.string()), std::string::npos) << message;
  EXPECT_NE(error_of([&] { formats::write_text_atomically(dir_, "x"); }).find("is a directory"),
            std::string::npos);
  EXPECT_TRUE(others("table.hpp").empty());
}

// A folder made later (render's image folder, report's output folder): fine when it exists or its
// nearest existing ancestor is a folder, refused (naming the ancestor) under a file.
TEST_F(Output, CreatableFolderNeedsAFolderAsItsNearestExistingAncestor) {
  EXPECT_NO_THROW(formats::check_creatable_folder(dir_, "out"));
  EXPECT_NO_THROW(formats::check_creatable_folder(dir_ / "a" / "b" / "c", "out"));
  EXPECT_NO_THROW(formats::check_creatable_folder("", "out"));  // the working directory
  std::ofstream(dir_ / "file") << "x";
  const std::string message =
      error_of([&] { formats::check_creatable_folder(dir_ / "file" / "sub", "out"); });
  EXPECT_NE(message.find("out: " + (dir_ / "file").string() + " is not a folder"),
            std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(dir_ / "a"));  // nothing made
}

TEST_F(Output, RefusesAnUnwritablePath) {
  // /proc accepts no new files, even for root.
  const std::string message = error_of(
      [&] { formats::write_asset_file("/proc/clothbake-test.cbk", sections(4, "x"), {}); });
  EXPECT_NE(message.find("/proc/clothbake-test.cbk"), std::string::npos) << message;
  if (::geteuid() != 0) {
    fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
    const std::string m2 =
        error_of([&] { formats::write_asset_file(dir_ / "a.cbk", sections(4, "x"), {}); });
    EXPECT_NE(m2.find("not writable"), std::string::npos) << m2;
  }
}

TEST_F(Output, RefusesToOverwriteANonAssetUnlessForced) {
  const fs::path out = dir_ / "notes.txt";
  { std::ofstream(out) << "precious notes\n"; }
  const std::string message =
      error_of([&] { formats::write_asset_file(out, sections(4, "x"), {}); });
  EXPECT_NE(message.find("is not a clothbake asset"), std::string::npos) << message;
  EXPECT_NE(message.find("--force"), std::string::npos) << message;
  EXPECT_EQ(read(out), "precious notes\n");
  formats::OutputOptions force;
  force.force = true;
  formats::write_asset_file(out, sections(4, "x"), force);
  EXPECT_TRUE(formats::looks_like_asset(out));
}

// Passes `budget` bytes to the file, then fails like a full disk.
class DiskFullSink : public formats::Sink {
 public:
  DiskFullSink(formats::Sink& inner, uint64_t budget) : inner_(inner), budget_(budget) {}
  void write(const void* data, std::size_t size) override {
    if (size > budget_) {
      inner_.write(data, std::size_t(budget_));
      budget_ = 0;
      throw_input_error("cannot write: No space left on device (simulated)");
    }
    inner_.write(data, size);
    budget_ -= size;
  }

 private:
  formats::Sink& inner_;
  uint64_t budget_;
};

TEST_F(Output, DiskFullMidWriteKeepsThePreviousAsset) {
  const fs::path out = dir_ / "a.cbk";
  formats::write_asset_file(out, sections(4, "good"), {});
  const std::string good = read(out);
  const auto next = sections(16, "next");
  const uint64_t size = formats::asset_size(next);
  for (uint64_t budget :
       {uint64_t(0), uint64_t(10), uint64_t(64), uint64_t(1000), size / 2, size - 1}) {
    formats::OutputOptions options;
    options.wrap_sink = [budget](formats::Sink& file) {
      return std::make_unique<DiskFullSink>(file, budget);
    };
    const std::string message = error_of([&] { formats::write_asset_file(out, next, options); });
    EXPECT_NE(message.find("No space left"), std::string::npos);
    EXPECT_EQ(read(out), good) << "budget " << budget;
    EXPECT_TRUE(others("a.cbk").empty()) << "temporary file left behind, budget " << budget;
  }
}

TEST_F(Output, FileSizeLimitInAChildIsAnErrorAndKeepsThePreviousAsset) {
  const fs::path out = dir_ / "a.cbk";
  formats::write_asset_file(out, sections(4, "good"), {});
  const std::string good = read(out);
  const auto next = sections(32, "big");
  ASSERT_GT(formats::asset_size(next), 8192u);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Child: write() fails with EFBIG past 4 KiB (SIGXFSZ ignored so that it returns).
    ::signal(SIGXFSZ, SIG_IGN);
    struct rlimit limit {
      4096, 4096
    };
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      formats::write_asset_file(out, next, {});
    } catch (const Error& e) {
      const std::string m = e.what();
      ::_exit(m.find("File too large") != std::string::npos && e.code() == ExitCode::Input ? 42
                                                                                           : 43);
    }
    ::_exit(44);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 42);
  EXPECT_EQ(read(out), good);
  EXPECT_TRUE(others("a.cbk").empty());
}

// A child process that writes `next` to `out` and pauses after 3000 bytes (the sink's test hook),
// with the CLI's signal handlers installed or not. Returns once the temporary file holds part of
// the asset (`partial` false if it never did).
pid_t start_paused_writer(const fs::path& out, const std::vector<formats::Section>& next,
                          bool handlers, bool& partial) {
  const pid_t pid = ::fork();
  if (pid < 0) return pid;
  if (pid == 0) {
    // A shell may start the test with SIGINT ignored, which the handlers would keep so.
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    if (handlers) install_temp_file_signal_handlers();
    ::setenv("CLOTHBAKE_TEST_PAUSE_AFTER_BYTES", "3000", 1);
    try {
      formats::write_asset_file(out, next, {});
    } catch (...) {
    }
    ::_exit(0);
  }
  partial = false;
  const std::string prefix = "." + out.filename().string() + ".tmp-";
  for (int i = 0; i < 500 && !partial; ++i) {
    for (const auto& e : fs::directory_iterator(out.parent_path()))
      if (e.path().filename().string().rfind(prefix, 0) == 0 && fs::file_size(e.path()) >= 3000)
        partial = true;
    if (!partial) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return pid;
}

TEST_F(Output, SigkillMidWriteLeavesThePreviousAssetIntact) {
  const fs::path out = dir_ / "a.cbk";
  formats::write_asset_file(out, sections(4, "good"), {});
  const std::string good = read(out);
  bool partial = false;
  const pid_t pid = start_paused_writer(out, sections(32, "killed"), true, partial);
  ASSERT_GE(pid, 0);
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(partial) << "the writer never paused mid-write";
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(read(out), good);
  reader::Asset asset;
  EXPECT_TRUE(asset.open_file(out.c_str()).ok());
  // SIGKILL cannot be caught: the only other file is the killed writer's temporary, named so that
  // it cannot be mistaken...
  const std::vector<std::string> left = others("a.cbk");
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].rfind(".a.cbk.tmp-", 0), 0u) << left[0];
  // ...and the next write to that output removes it (its lock died with the process).
  formats::write_asset_file(out, sections(8, "next"), {});
  EXPECT_TRUE(others("a.cbk").empty());
  EXPECT_TRUE(asset.open_file(out.c_str()).ok());
}

// SIGTERM and SIGINT mid-write: the handler removes the temporary file and the process still ends
// by the signal; the previous asset is untouched.
TEST_F(Output, SigtermAndSigintMidWriteRemoveTheTemporaryFile) {
  const fs::path out = dir_ / "a.cbk";
  formats::write_asset_file(out, sections(4, "good"), {});
  const std::string good = read(out);
  for (const int signo : {SIGTERM, SIGINT}) {
    SCOPED_TRACE(signo);
    bool partial = false;
    const pid_t pid = start_paused_writer(out, sections(32, "interrupted"), true, partial);
    ASSERT_GE(pid, 0);
    ::kill(pid, signo);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(partial) << "the writer never paused mid-write";
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), signo);
    EXPECT_EQ(read(out), good);
    EXPECT_TRUE(others("a.cbk").empty());
  }
}

// A temporary of the same output whose lock is free (its writer was killed) is removed by the next
// write; one that a live process holds locked, and files of any other name or kind, are not.
TEST_F(Output, NextWriteRemovesOnlyItsOwnUnlockedStaleTemporaries) {
  const fs::path out = dir_ / "a.cbk";
  auto make = [&](const std::string& name) { std::ofstream(dir_ / name) << "partial " << name; };
  make(".a.cbk.tmp-Ab3xZ9");  // stale: removed
  make(".a.cbk.tmp-000000");  // stale: removed
  make(".a.cbk.tmp-Locked");  // held by another process: stays
  const std::vector<std::string> unrelated = {
      ".b.cbk.tmp-Ab3xZ9",      // another output
      ".xa.cbk.tmp-Ab3xZ9",     // another output whose name ends like this one
      ".a.cbk.tmp-Ab3xZ",       // five characters: not a mkstemps name
      ".a.cbk.tmp-Ab3xZ99",     // seven
      ".a.cbk.tmp-Ab3x-9",      // not [A-Za-z0-9]
      ".a.cbk.tmp-Ab3xZ9.exr",  // another suffix (an image export to a.cbk would use it)
      "a.cbk.tmp-Ab3xZ9",       // not hidden
      ".a.cbk.tmp-",            // no random part
      "a.cbk.old",
  };
  for (const auto& name : unrelated)
    make(name);
  // A symbolic link and a directory with a temporary's name are not regular files: left alone (the
  // link's target too).
  make("target");
  fs::create_symlink("target", dir_ / ".a.cbk.tmp-Link00");
  fs::create_directory(dir_ / ".a.cbk.tmp-Dir000");

  // Another process holds the flock of one candidate, as a live writer does.
  int ready[2], release[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(release), 0);
  const pid_t holder = ::fork();
  ASSERT_GE(holder, 0);
  if (holder == 0) {
    const int fd = ::open((dir_ / ".a.cbk.tmp-Locked").c_str(), O_RDONLY);
    const char ok = (fd >= 0 && ::flock(fd, LOCK_EX) == 0) ? 'y' : 'n';
    (void)!::write(ready[1], &ok, 1);
    char c;
    (void)!::read(release[0], &c, 1);
    ::_exit(0);
  }
  char ok = 0;
  ASSERT_EQ(::read(ready[0], &ok, 1), 1);
  ASSERT_EQ(ok, 'y');

  formats::write_asset_file(out, sections(4, "fresh"), {});
  reader::Asset asset;
  EXPECT_TRUE(asset.open_file(out.c_str()).ok());
  EXPECT_FALSE(fs::exists(dir_ / ".a.cbk.tmp-Ab3xZ9"));
  EXPECT_FALSE(fs::exists(dir_ / ".a.cbk.tmp-000000"));
  EXPECT_TRUE(fs::exists(dir_ / ".a.cbk.tmp-Locked"));
  for (const auto& name : unrelated)
    EXPECT_EQ(read(dir_ / name), "partial " + name) << name;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / ".a.cbk.tmp-Link00")));
  EXPECT_EQ(read(dir_ / "target"), "partial target");
  EXPECT_TRUE(fs::is_directory(dir_ / ".a.cbk.tmp-Dir000"));

  // Once the holder is gone its file is stale too.
  (void)!::write(release[1], "x", 1);
  int status = 0;
  ASSERT_EQ(::waitpid(holder, &status, 0), holder);
  for (int fd : {ready[0], ready[1], release[0], release[1]})
    ::close(fd);
  EXPECT_EQ(formats::remove_stale_temp_files(out), 1);
  EXPECT_FALSE(fs::exists(dir_ / ".a.cbk.tmp-Locked"));
  EXPECT_TRUE(fs::exists(dir_ / ".b.cbk.tmp-Ab3xZ9"));
}

// While a TempFile exists its file is locked: another writer's clean-up leaves it alone, and a
// registered temporary is what the signal handler removes.
TEST_F(Output, ALiveTemporaryIsLockedAndRegistered) {
  const fs::path out = dir_ / "a.cbk";
  {
    formats::TempFile live(out);
    EXPECT_EQ(formats::remove_stale_temp_files(out), 0);
    EXPECT_TRUE(fs::exists(live.path()));
    const int fd = ::open(live.path().c_str(), O_RDONLY);
    ASSERT_GE(fd, 0);
    EXPECT_NE(::flock(fd, LOCK_EX | LOCK_NB), 0) << "the live temporary is not locked";
    ::close(fd);
  }
  EXPECT_TRUE(others("").empty());
  // The registry in isolation: a registered path is removed, an unregistered one is not.
  std::ofstream(dir_ / "registered") << "x";
  std::ofstream(dir_ / "forgotten") << "x";
  const int kept = register_temp_path((dir_ / "forgotten").c_str());
  unregister_temp_path(kept);
  ASSERT_GE(register_temp_path((dir_ / "registered").c_str()), 0);
  EXPECT_EQ(unlink_registered_temp_paths(), 1);
  EXPECT_FALSE(fs::exists(dir_ / "registered"));
  EXPECT_TRUE(fs::exists(dir_ / "forgotten"));
  EXPECT_EQ(register_temp_path(std::string(kTempPathMax, 'x').c_str()), -1);
  // A registered directory is removed after the registered files in it, whatever the order of
  // registration.
  fs::create_directory(dir_ / "tmpdir");
  std::ofstream(dir_ / "tmpdir" / "file") << "x";
  ASSERT_GE(register_temp_path((dir_ / "tmpdir").c_str(), true), 0);
  ASSERT_GE(register_temp_path((dir_ / "tmpdir" / "file").c_str()), 0);
  EXPECT_EQ(unlink_registered_temp_paths(), 2);
  EXPECT_FALSE(fs::exists(dir_ / "tmpdir"));
}

// Temporary names stay within 255 bytes, and two long names that share their first 200 bytes
// still have prefixes of their own (so neither cleans up the other's temporaries).
TEST_F(Output, LongNamesHaveDistinctTemporaryPrefixes) {
  const std::string stem(240, 'n');
  const fs::path a = dir_ / (stem + "a.cbk"), b = dir_ / (stem + "b.cbk");
  EXPECT_NE(formats::temp_file_prefix(a), formats::temp_file_prefix(b));
  EXPECT_LE(formats::temp_file_prefix(a).size() + 6, 255u);
  EXPECT_EQ(formats::temp_file_prefix(dir_ / "a.cbk"), ".a.cbk.tmp-");
  formats::write_asset_file(a, sections(4, "long"), {});
  EXPECT_TRUE(fs::exists(a));
}

TEST_F(Output, ReaderReportsIoErrors) {
  reader::Asset asset;
  reader::Status status = asset.open_file((dir_ / "missing.cbk").c_str());
  EXPECT_EQ(status.code(), reader::ErrorCode::Io);
  EXPECT_NE(std::string(status.message()).find("missing.cbk"), std::string::npos);
  status = asset.open_file(dir_.c_str());
  EXPECT_EQ(status.code(), reader::ErrorCode::Io);
  const fs::path empty = dir_ / "empty.cbk";
  std::ofstream{empty};
  status = asset.open_file(empty.c_str());
  EXPECT_EQ(status.code(), reader::ErrorCode::Truncated);
  const fs::path text = dir_ / "text.cbk";
  {
    std::ofstream(text)
        << "hello, this is not an asset at all, but it is long enough to be one......";
  }
  status = asset.open_file(text.c_str());
  EXPECT_EQ(status.code(), reader::ErrorCode::NotAnAsset);
  EXPECT_STREQ(status.check_id(), "CBK-E001");
}

}  // namespace

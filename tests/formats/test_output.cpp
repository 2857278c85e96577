// Atomic asset files: bad output paths, refusing to overwrite non-assets, simulated disk-full and
// short writes (fault-injecting sink and RLIMIT_FSIZE in a child), and a SIGKILL mid-write. In
// every failure the previous file at the output path is intact and no partial file is left.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "common/error.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/writer/asset_writer.hpp"
#include "formats/writer/atomic_file.hpp"
#include "tests/formats/test_fabric.hpp"

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
    auto s = fabric_record_sections(fabric);
    for (auto& m : feature_map_sections(fabric.maps))
      s.push_back(std::move(m));
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
    try {
      f();
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Input) << e.what();
      return e.what();
    }
    ADD_FAILURE() << "no error";
    return "";
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

TEST_F(Output, SigkillMidWriteLeavesThePreviousAssetIntact) {
  const fs::path out = dir_ / "a.cbk";
  formats::write_asset_file(out, sections(4, "good"), {});
  const std::string good = read(out);
  const auto next = sections(32, "killed");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::setenv("CLOTHBAKE_TEST_PAUSE_AFTER_BYTES", "3000", 1);
    try {
      formats::write_asset_file(out, next, {});
    } catch (...) {
    }
    ::_exit(0);
  }
  // Wait until the temporary file holds part of the asset, then kill the writer.
  bool partial = false;
  for (int i = 0; i < 500 && !partial; ++i) {
    for (const auto& e : fs::directory_iterator(dir_))
      if (e.path().filename() != "a.cbk" && fs::file_size(e.path()) >= 3000) partial = true;
    if (!partial) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(partial) << "the writer never paused mid-write";
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(read(out), good);
  reader::Asset asset;
  EXPECT_TRUE(asset.open_file(out.c_str()).ok());
  // The only other file is the killed writer's temporary, named so that it cannot be mistaken.
  for (const auto& name : others("a.cbk"))
    EXPECT_EQ(name.rfind(".a.cbk.tmp-", 0), 0u) << name;
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

// `clothbake verify` end to end: a faithful asset exits 0 with a JSON report, a tampered one 5
// (verification failed), an unreadable or incomplete asset 2/3, a bad command line 1.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "formats/writer/atomic_file.hpp"
#include "verify_fixtures.hpp"

namespace fs = std::filesystem;
using namespace clothbake;

namespace {

struct CliRun {
  int code = -1;
  std::string out, err;
};

CliRun run(const std::string& args) {
  const fs::path err_file =
      fs::temp_directory_path() / ("clothbake_verify_err_" + std::to_string(::getpid()));
  const std::string cmd = std::string(CLOTHBAKE_EXE) + " " + args + " 2>" + err_file.string();
  CliRun r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0)
    r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err_file);
  std::stringstream ss;
  ss << in.rdbuf();
  r.err = ss.str();
  fs::remove(err_file);
  return r;
}

class CliVerify : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("clothbake_verify_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    toml_ = dir_ / "fabric.toml";
    std::ofstream(toml_) << "name = \"verify test\"\n[weave]\nname = \"twill2/1\"\n"
                            "[[yarn]]\nname = \"warp\"\nroughness = 0.3\n"
                            "[[yarn]]\nname = \"weft\"\nroughness = 0.2\n"
                            "[bake]\nresolution = 24\n";
    fabric_ = load_fabric(toml_.string());
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name,
                    const std::function<void(std::vector<formats::Section>&)>& tamper = {}) {
    tables::RadianceOptions o;
    o.bins_per_side = 6;
    o.warn_unresolved = false;
    const auto sections = verify_testing::asset_sections(fabric_, 3, o, tamper);
    const fs::path path = dir_ / name;
    formats::write_asset_file(path, sections, formats::OutputOptions{});
    return path.string();
  }

  fs::path dir_, toml_;
  Fabric fabric_;
};

}  // namespace

TEST_F(CliVerify, FaithfulAssetPassesWithJson) {
  const std::string asset = write("good.cbk");
  CliRun r = run("verify " + asset + " --fabric " + toml_.string() + " --json --samples 35");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["passed"], true);
  EXPECT_EQ(doc["tables"][0]["kind"], "specular");
  EXPECT_LE(doc["tables"][0]["sat_error_max"].get<double>(), 1e-5);
  // The human summary names the classes and the verdict.
  CliRun text = run("verify " + asset + " --fabric " + toml_.string() + " --samples 35");
  EXPECT_EQ(text.code, 0);
  EXPECT_NE(text.out.find("verification passed"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("tiles"), std::string::npos) << text.out;
}

TEST_F(CliVerify, TamperedTablesExitFive) {
  const std::string asset = write("bad.cbk", [](std::vector<formats::Section>& s) {
    auto* sat = verify_testing::sat_section(s, 0);
    auto* v = reinterpret_cast<uint32_t*>(sat->payload.data());
    const std::size_t count = sat->payload.size() / 4;
    for (std::size_t i = count / 2; i < count; ++i)
      v[i] += 50000000u;  // a jump in the SAT
  });
  CliRun r = run("verify " + asset + " --fabric " + toml_.string() + " --samples 35");
  EXPECT_EQ(r.code, 5) << r.err;
  EXPECT_NE(r.err.find("verification failed"), std::string::npos) << r.err;
  // A generous threshold accepts the same asset... no: the jump is far above any threshold.
  CliRun loose =
      run("verify " + asset + " --fabric " + toml_.string() + " --samples 35 --max-rel-error 0.5");
  EXPECT_EQ(loose.code, 5);
}

TEST_F(CliVerify, BadInputsHaveTheirExitCodes) {
  const std::string asset = write("good.cbk");
  EXPECT_EQ(run("verify " + (dir_ / "missing.cbk").string() + " --fabric " + toml_.string()).code,
            2);
  const std::string bare = write("bare.cbk", [](std::vector<formats::Section>& s) {
    std::erase_if(s, [](const formats::Section& x) {
      return x.type == reader::SectionType::RadianceRawTables;
    });
  });
  CliRun r = run("verify " + bare + " --fabric " + toml_.string());
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("no raw specular"), std::string::npos) << r.err;
  EXPECT_EQ(run("verify " + asset).code, 1);  // --fabric missing
  EXPECT_EQ(run("verify " + asset + " --fabric " + toml_.string() + " --samples 0").code, 1);
  EXPECT_EQ(run("verify " + asset + " --fabric " + toml_.string() + " --max-rel-error -1").code, 1);
}

// `clothbake export` of Integral-Radiance tables and of the cluster label map, end to end on two
// small baked assets of one fabric (raw tables from `--stages tables`, compressed ones from the
// default bake, which drops the raw ones): the EXR pixels equal the reader's per-texel
// values (raw: texel_value of the quantised tables; compressed: the decompressed values), one
// cluster or the sum over all clusters; bad indices and lobes exit with their codes and write
// nothing.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>

#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/image_io/image_io.hpp"
#include "formats/reader/cluster_sections.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "tests/support/run_cli.hpp"

using namespace clothbake;
namespace fs = std::filesystem;

namespace {

using clothbake::test_support::CliRun;

// `clothbake export ARGS` (split by the shell).
CliRun run(const std::string& args) {
  return clothbake::test_support::run_clothbake_line("export " + args);
}

class ExportRadiance : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("clothbake_export_radiance_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    Fabric fabric = fabric_from_named_weave("twill2/1", 16).fabric;
    fabric.bake.visibility_dirs = 8;
    fabric.bake.radiance_dirs = 4;
    fabric.bake.clusters = 3;
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.output_path = asset();
    request.stages = {"compress"};
    pipeline::bake(request, stages::bake_stages());
    request.output_path = raw_asset();
    request.stages = {"tables"};
    pipeline::bake(request, stages::bake_stages());
    request.output_path = bare();
    request.stages = {"feature_maps"};
    pipeline::bake(request, stages::bake_stages());
    bytes_ = new std::vector<std::byte>(read_bytes(asset()));
    raw_bytes_ = new std::vector<std::byte>(read_bytes(raw_asset()));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete bytes_;
    delete raw_bytes_;
  }
  static std::vector<std::byte> read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::byte> bytes(chars.size());
    std::memcpy(bytes.data(), chars.data(), chars.size());
    return bytes;
  }
  static std::string asset() { return (*dir_ / "asset.cbk").string(); }
  static std::string raw_asset() { return (*dir_ / "raw.cbk").string(); }
  static std::string bare() { return (*dir_ / "bare.cbk").string(); }
  static std::string out(const std::string& name) { return (*dir_ / name).string(); }

  static fs::path* dir_;
  static std::vector<std::byte>* bytes_;
  static std::vector<std::byte>* raw_bytes_;
};
fs::path* ExportRadiance::dir_ = nullptr;
std::vector<std::byte>* ExportRadiance::bytes_ = nullptr;
std::vector<std::byte>* ExportRadiance::raw_bytes_ = nullptr;

TEST_F(ExportRadiance, RawAndCompressedTablesEqualTheReadersTexelValues) {
  reader::Asset a, ra;
  ASSERT_TRUE(a.open_memory(bytes_->data(), bytes_->size()).ok());
  ASSERT_TRUE(ra.open_memory(raw_bytes_->data(), raw_bytes_->size()).ok());
  reader::RawRadianceTables raw;
  reader::CompressedRadianceTables packed;
  ASSERT_TRUE(raw.open(ra, reader::RadianceTableKind::Specular).ok());
  ASSERT_TRUE(packed.open(a, reader::RadianceTableKind::Specular).ok());
  const uint32_t n = raw.resolution();
  for (uint32_t bin : {0u, 5u}) {
    for (int cluster = -1; cluster < int(raw.cluster_count()); ++cluster) {
      // Appends only (no "literal" + string temporaries: GCC 12 -Wrestrict false positive).
      std::string index = std::to_string(bin);
      if (cluster >= 0) {
        index += ',';
        index += std::to_string(cluster);
      }
      const std::string raw_out = out("raw_" + index + ".exr");
      const std::string packed_out = out("packed_" + index + ".exr");
      CliRun r =
          run(raw_asset() + " --section radiance_tables --index " + index + " -o " + raw_out);
      ASSERT_EQ(r.code, 0) << r.err;
      r = run(asset() + " --section radiance_compressed --lobe specular_transmission --index " +
              index + " -o " + packed_out);
      ASSERT_EQ(r.code, 0) << r.err;
      const Image ri = read_image(raw_out), pi = read_image(packed_out);
      ASSERT_EQ(ri.width, int(n));
      ASSERT_EQ(ri.height, int(n));
      ASSERT_EQ(ri.channels, 1);
      ASSERT_EQ(pi.width, int(n));
      double largest_raw = 0, largest_packed = 0;
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x) {
          double expected_raw = 0, expected_packed = 0;
          for (uint32_t c = 0; c < raw.cluster_count(); ++c) {
            if (cluster >= 0 && c != uint32_t(cluster)) continue;
            const int column = raw.column_of_cluster(c);
            if (column >= 0) expected_raw += raw.texel_value(bin, x, y, uint32_t(column));
          }
          if (cluster < 0 || packed.cluster_of_texel(x, y) == cluster)
            expected_packed = packed.texel_value(bin, x, y);
          const std::size_t t = std::size_t(y) * n + x;
          EXPECT_NEAR(ri.pixels[t], expected_raw, 1e-6 * (1 + std::abs(expected_raw)));
          EXPECT_NEAR(pi.pixels[t], expected_packed, 1e-6 * (1 + std::abs(expected_packed)));
          largest_raw = std::max(largest_raw, expected_raw);
          largest_packed = std::max(largest_packed, expected_packed);
        }
      // The tolerances are mostly absolute (1e-6): the tables must hold values far above them for
      // the comparison to mean anything (an all-zero export would otherwise pass).
      if (cluster < 0) {
        EXPECT_GT(largest_raw, 1e-2) << "bin " << bin << ": raw values too small to test";
        EXPECT_GT(largest_packed, 1e-2) << "bin " << bin << ": compressed values too small to test";
      }
    }
  }
}

TEST_F(ExportRadiance, LabelMapIsTheClusterLabels) {
  reader::Asset a;
  ASSERT_TRUE(a.open_memory(bytes_->data(), bytes_->size()).ok());
  reader::VisibilityClusterView labels;
  ASSERT_TRUE(labels.open(a).ok());
  const std::string path = out("labels.exr");
  const CliRun r = run(asset() + " --section cluster_labels -o " + path);
  ASSERT_EQ(r.code, 0) << r.err;
  const Image image = read_image(path);
  const int n = int(labels.resolution());
  ASSERT_EQ(image.width, n);
  ASSERT_EQ(image.height, n);
  ASSERT_EQ(image.channels, 1);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      EXPECT_EQ(image.pixels[std::size_t(y) * n + x], float(labels.label(x, y)));
}

TEST_F(ExportRadiance, BadRequestsExitWithTheirCodesAndWriteNothing) {
  const std::string path = out("bad.exr");
  struct Case {
    std::string args;
    int code;
    std::string mentions;
  };
  const Case cases[] = {
      {"--section radiance_tables -o " + path, 2, "--index"},
      {"--section radiance_tables --index 16 -o " + path, 2, "bin 16"},
      {"--section radiance_tables --index 1,250 -o " + path, 2, "cluster 250"},
      {"--section radiance_tables --index 1,2,0 -o " + path, 2, "--index"},
      {"--section radiance_tables --lobe sheen --index 0 -o " + path, 1, "--lobe"},
      {"--section radiance_tables --lobe specular --index 0 -o " + path, 1, "--lobe"},
      {"--section radiance_tables --instance 1 --index 0 -o " + path, 1, "--instance"},
      {"--section radiance_compressed --index 0 -o " + path, 2, "radiance_compressed"},
      {"--section height --lobe specular_reflection -o " + path, 1, "--lobe"},
  };
  for (const Case& c : cases) {
    const CliRun r = run(raw_asset() + " " + c.args);
    EXPECT_EQ(r.code, c.code) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(path)) << c.args;
  }
  // No tables in the asset: an input error naming the section; the same for the compressed ones'
  // bin range.
  CliRun r = run(bare() + " --section radiance_compressed --index 0 -o " + path);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("radiance_compressed"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path));
  r = run(asset() + " --section radiance_compressed --index 16 -o " + path);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("bin 16"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path));
  // A damaged table section (checksum mismatch): invalid asset.
  const std::string damaged = out("damaged.cbk");
  fs::copy_file(raw_asset(), damaged, fs::copy_options::overwrite_existing);
  {
    reader::Asset a;
    ASSERT_TRUE(a.open_memory(raw_bytes_->data(), raw_bytes_->size()).ok());
    reader::SectionInfo s;
    ASSERT_TRUE(a.find(reader::SectionType::RadianceRawTables, 3, &s).ok());
    std::fstream f(damaged, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(s.offset + s.stored_size / 2));
    f.put(char(0x55));
  }
  r = run(damaged + " --section radiance_tables --index 0 -o " + path);
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace

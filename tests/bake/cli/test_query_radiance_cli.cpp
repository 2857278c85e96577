// `clothbake query ASSET radiance` end to end on two small baked assets of one fabric, one with raw
// tables (`--stages tables`) and one with compressed tables (the default bake drops the raw ones):
// the CLI's JSON answers equal a direct sum over the stored texel values (raw:
// the quantised table values; compressed: the decompressed ones) with bilinear bin weights and the
// covered area of every texel, on footprints that wrap and span tiles; the JSON says which
// representation answered; bad arguments exit 1 naming the option, missing tables exit 2.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "tests/support/run_cli.hpp"

using namespace clothbake;
namespace fs = std::filesystem;

namespace {

using clothbake::test_support::CliRun;

// `clothbake query ARGS` (split by the shell).
CliRun run(const std::string& args) {
  return clothbake::test_support::run_clothbake_line("query " + args);
}

// Direct sum over the texels a rectangle covers (each with its covered area), of
// sum_b w_b value(bin b, texel) for texels of `cluster`; value(bin, x, y, &cluster_of_texel).
template <class Value>
double direct_sum(const std::array<double, 4>& rect, uint32_t n, const reader::BinWeights& w,
                  Value value) {
  double total = 0;
  for (int64_t y = int64_t(std::floor(rect[1])); double(y) < rect[3]; ++y) {
    const double cy = std::min(rect[3], double(y + 1)) - std::max(rect[1], double(y));
    if (cy <= 0) continue;
    for (int64_t x = int64_t(std::floor(rect[0])); double(x) < rect[2]; ++x) {
      const double cx = std::min(rect[2], double(x + 1)) - std::max(rect[0], double(x));
      if (cx <= 0) continue;
      const uint32_t tx = uint32_t(((x % n) + n) % n), ty = uint32_t(((y % n) + n) % n);
      double v = 0;
      for (uint32_t k = 0; k < w.count; ++k)
        v += w.weight[k] * value(w.bin[k], tx, ty);
      total += cx * cy * v;
    }
  }
  return total;
}

class QueryRadianceCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("clothbake_query_radiance_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    Fabric fabric = fabric_from_named_weave("twill2/1", 16).fabric;
    fabric.bake.visibility_dirs = 8;
    fabric.bake.radiance_dirs = 6;
    fabric.bake.clusters = 3;
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.output_path = packed();
    request.stages = {"compress"};
    pipeline::bake(request, stages::bake_stages());
    request.output_path = raw_only();
    request.stages = {"tables"};
    pipeline::bake(request, stages::bake_stages());
    request.output_path = bare();
    request.stages = {"feature_maps"};
    pipeline::bake(request, stages::bake_stages());
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string packed() { return (*dir_ / "packed.cbk").string(); }
  static std::string raw_only() { return (*dir_ / "raw.cbk").string(); }
  static std::string bare() { return (*dir_ / "bare.cbk").string(); }

  static fs::path* dir_;
};
fs::path* QueryRadianceCli::dir_ = nullptr;

std::vector<std::byte> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> bytes(chars.size());
  std::memcpy(bytes.data(), chars.data(), chars.size());
  return bytes;
}

TEST_F(QueryRadianceCli, AnswersEqualDirectSumsOnRawAndCompressedTables) {
  const std::vector<std::byte> raw_bytes = read_bytes(raw_only());
  const std::vector<std::byte> packed_bytes = read_bytes(packed());
  reader::Asset raw_asset, packed_asset;
  ASSERT_TRUE(raw_asset.open_memory(raw_bytes.data(), raw_bytes.size()).ok());
  ASSERT_TRUE(packed_asset.open_memory(packed_bytes.data(), packed_bytes.size()).ok());
  reader::RawRadianceTables raw;
  reader::CompressedRadianceTables packed_tables;
  ASSERT_TRUE(raw.open(raw_asset, reader::RadianceTableKind::Specular).ok());
  ASSERT_TRUE(packed_tables.open(packed_asset, reader::RadianceTableKind::Specular).ok());
  ASSERT_EQ(packed_tables.cluster_count(), raw.cluster_count());
  const uint32_t n = raw.resolution();
  ASSERT_EQ(n, 16u);
  ASSERT_EQ(raw.bins_per_side(), 6u);
  const std::array<std::array<double, 4>, 3> rects = {
      {{-3.5, 2.25, 20.0, 9.0},       // wraps, wider than a tile
       {15.5, 15.5, 16.5, 16.5},      // 4 partial texels around the tile corner
       {-40.25, -7.5, 5.75, 30.0}}};  // many tiles
  const std::array<std::array<double, 3>, 2> hs = {
      {{0.3, -0.2, 0.8}, {-0.9, 0.1, -0.3}}};  // the second folds to the upper side
  for (const char* source : {"raw", "compressed"}) {
    const bool is_raw = std::string(source) == "raw";
    for (const auto& rect : rects)
      for (const auto& h : hs) {
        char args[256];
        std::snprintf(args, sizeof args,
                      " radiance --lobe specular_reflection --h %.17g,%.17g,%.17g --rect "
                      "%.17g,%.17g,%.17g,%.17g --tables %s --json",
                      h[0], h[1], h[2], rect[0], rect[1], rect[2], rect[3], source);
        const CliRun r = run((is_raw ? raw_only() : packed()) + args);
        ASSERT_EQ(r.code, 0) << r.err;
        const auto j = nlohmann::json::parse(r.out);
        EXPECT_EQ(j["source"], source);
        EXPECT_EQ(j["table"], "specular");
        reader::BinWeights w;
        ASSERT_TRUE(reader::radiance_bin_weights(6, h.data(), &w).ok());
        ASSERT_EQ(j["clusters"].size(), raw.cluster_count());
        double sum_of_all = 0;
        for (uint32_t c = 0; c < raw.cluster_count(); ++c) {
          double expected;
          if (is_raw) {
            const int column = raw.column_of_cluster(c);
            expected =
                column < 0 ? 0.0 : direct_sum(rect, n, w, [&](uint32_t b, uint32_t x, uint32_t y) {
                  return raw.texel_value(b, x, y, uint32_t(column));
                });
          } else {
            expected = direct_sum(rect, n, w, [&](uint32_t b, uint32_t x, uint32_t y) {
              return packed_tables.cluster_of_texel(x, y) == int(c)
                         ? packed_tables.texel_value(b, x, y)
                         : 0.0;
            });
          }
          const double got = j["clusters"][c]["F"].get<double>();
          EXPECT_NEAR(got, expected, 1e-6 * (1 + std::abs(expected)))
              << source << " cluster " << c << " rect " << rect[0] << "," << rect[1];
          sum_of_all += expected;
        }
        EXPECT_NEAR(j["total"].get<double>(), sum_of_all, 1e-6 * (1 + std::abs(sum_of_all)));
        const double area = (rect[2] - rect[0]) * (rect[3] - rect[1]);
        EXPECT_DOUBLE_EQ(j["area_texels"].get<double>(), area);
      }
  }
  // One cluster alone equals its entry in the all-cluster answer; auto takes the compressed tables
  // when there are no raw ones.
  const CliRun all = run(packed() +
                         " radiance --lobe specular_reflection --h 0.3,-0.2,0.8 --rect "
                         "-3.5,2.25,20,9 --json");
  const CliRun one = run(packed() +
                         " radiance --lobe specular_reflection --cluster 1 --h "
                         "0.3,-0.2,0.8 --rect -3.5,2.25,20,9 --json");
  ASSERT_EQ(all.code, 0) << all.err;
  ASSERT_EQ(one.code, 0) << one.err;
  const auto ja = nlohmann::json::parse(all.out), jo = nlohmann::json::parse(one.out);
  EXPECT_EQ(ja["source"], "compressed");
  ASSERT_EQ(jo["clusters"].size(), 1u);
  EXPECT_EQ(jo["clusters"][0]["cluster"], 1);
  EXPECT_DOUBLE_EQ(jo["total"].get<double>(), ja["clusters"][1]["F"].get<double>());
  // The text form names the representation.
  const CliRun text = run(packed() +
                          " radiance --lobe specular_transmission --h 0,0,1 --rect "
                          "0,0,16,16 --tables compressed");
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("compressed"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("total: F ="), std::string::npos) << text.out;
}

TEST_F(QueryRadianceCli, BadArgumentsExitOneNamingTheOption) {
  const std::string base = packed() + " radiance ";
  struct Case {
    std::string args, option;
  };
  const Case cases[] = {
      {"--h 0,0,1 --rect 0,0,1,1", "--lobe"},
      {"--lobe specular_reflection --rect 0,0,1,1", "--h"},
      {"--lobe specular_reflection --h 0,0,1", "--rect"},
      {"--lobe specular --h 0,0,1 --rect 0,0,1,1", "--lobe"},
      {"--lobe sheen --h 0,0,1 --rect 0,0,1,1", "--lobe"},
      {"--lobe specular_reflection --cluster 250 --h 0,0,1 --rect 0,0,1,1", "--cluster"},
      {"--lobe specular_reflection --h 0,0,0 --rect 0,0,1,1", "--h"},
      {"--lobe specular_reflection --h 0,nan,1 --rect 0,0,1,1", "--h"},
      {"--lobe specular_reflection --h 0,1 --rect 0,0,1,1", "--h"},
      {"--lobe specular_reflection --h 0,0,1 --rect 2,0,1,1", "--rect"},
      {"--lobe specular_reflection --h 0,0,1 --rect 0,0,1,1 --texel 1,1", "--texel"},
      {"--lobe specular_reflection --h 0,0,1 --rect 0,0,1,1 --tables lossy", "--tables"},
  };
  for (const Case& c : cases) {
    const CliRun r = run(base + c.args);
    EXPECT_EQ(r.code, 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.option), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << c.args;
  }
  // --lobe on another kind is refused too.
  const CliRun other =
      run(packed() + " parallax --dir 0,0,1 --texel 1,1 --lobe specular_reflection");
  EXPECT_EQ(other.code, 1) << other.err;
}

TEST_F(QueryRadianceCli, MissingTablesExitTwo) {
  // No tables at all.
  CliRun r = run(bare() + " radiance --lobe specular_reflection --h 0,0,1 --rect 0,0,1,1");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("specular"), std::string::npos) << r.err;
  // Raw tables only: asking for the compressed ones is an input error; auto answers from raw.
  r = run(raw_only() +
          " radiance --lobe specular_reflection --h 0,0,1 --rect 0,0,1,1 --tables compressed");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("compressed"), std::string::npos) << r.err;
  r = run(raw_only() + " radiance --lobe specular_reflection --h 0,0,1 --rect 0,0,1,1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["source"], "raw");
  // Compressed tables only: asking for raw ones is an input error.
  r = run(packed() + " radiance --lobe specular_reflection --h 0,0,1 --rect 0,0,1,1 --tables raw");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("raw"), std::string::npos) << r.err;
  // A missing file.
  r = run((*dir_ / "missing.cbk").string() +
          " radiance --lobe specular_reflection --h 0,0,1 --rect 0,0,1,1");
  EXPECT_EQ(r.code, 2) << r.err;
}

}  // namespace

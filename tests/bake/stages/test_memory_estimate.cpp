// The up-front peak-memory estimate (bake/stages/memory_estimate.hpp): monotone in every size
// setting, the raw tables' exact size as a lower bound, only the stages that run, and the
// refusal naming the [bake] keys.
#include "bake/stages/memory_estimate.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.hpp"
#include "compress/compress_settings.hpp"

using namespace clothbake;
using stages::estimate_bake_memory;
using stages::MemoryEstimateInput;

namespace {

MemoryEstimateInput input(int resolution = 256) {
  MemoryEstimateInput in;
  in.bake.resolution = resolution;
  in.compression = compress::settings_from_bake(in.bake);
  in.threads = 2;
  return in;
}

double peak(const MemoryEstimateInput& in) {
  return estimate_bake_memory(in).peak_bytes;
}

double stage_peak(const MemoryEstimateInput& in, const std::string& stage) {
  for (const auto& s : estimate_bake_memory(in).stages)
    if (s.stage == stage) return s.peak_bytes;
  ADD_FAILURE() << "no stage " << stage;
  return 0;
}

MemoryEstimateInput raw_tables(MemoryEstimateInput in) {
  in.compression.enabled = false;
  return in;
}

}  // namespace

TEST(MemoryEstimate, GrowsWithEverySizeSetting) {
  for (bool compressed : {true, false}) {
    SCOPED_TRACE(compressed ? "compressed" : "raw tables");
    auto base = [&](int resolution) {
      auto in = input(resolution);
      return compressed ? in : raw_tables(in);
    };
    double last = 0;
    for (int n : {16, 64, 256, 1024, 4096}) {
      const double p = peak(base(n));
      EXPECT_GT(p, last) << "resolution " << n;
      last = p;
    }
    last = 0;
    for (int d : {2, 8, 32, 128, 256}) {
      auto in = base(128);
      in.bake.radiance_dirs = d;
      // Small tables: the peak is the parallax stage's; the tables' own stage grows strictly.
      const double p = stage_peak(in, compressed ? "compress" : "tables");
      EXPECT_GT(p, last) << "radiance_dirs " << d;
      EXPECT_GE(peak(in), p);
      last = p;
    }
    // The peak may be another stage's; the stage that depends on the setting grows strictly.
    last = 0;
    double last_stage = 0;
    for (int d : {2, 16, 64, 256}) {
      auto in = base(128);
      in.bake.parallax_dirs = d;
      EXPECT_GE(peak(in), last) << "parallax_dirs " << d;
      EXPECT_GT(stage_peak(in, "parallax"), last_stage) << "parallax_dirs " << d;
      last = peak(in);
      last_stage = stage_peak(in, "parallax");
    }
    last = last_stage = 0;
    for (int d : {2, 16, 64, 256}) {
      auto in = base(128);
      in.bake.visibility_dirs = d;
      EXPECT_GE(peak(in), last) << "visibility_dirs " << d;
      EXPECT_GT(stage_peak(in, "visibility"), last_stage) << "visibility_dirs " << d;
      last = peak(in);
      last_stage = stage_peak(in, "visibility");
    }
    last = 0;
    for (int k : {1, 4, 16, 64}) {
      auto in = base(128);
      in.bake.clusters = k;
      const double p = peak(in);
      EXPECT_GE(p, last) << "clusters " << k;
      last = p;
      // The raw tables hold one SAT per cluster.
      if (!compressed && k > 1) {
        auto fewer = in;
        fewer.bake.clusters = k / 4;
        EXPECT_GT(stage_peak(in, "tables"), stage_peak(fewer, "tables")) << "clusters " << k;
      }
    }
  }
}

TEST(MemoryEstimate, RawTablesAreAtLeastTheirSatsAndCompressionAtLeastItsVectors) {
  auto in = raw_tables(input(256));
  in.bake.radiance_dirs = 256;
  in.bake.clusters = 64;
  // 256^2 bins x 256^2 texels x 64 clusters x 4 bytes (u32 at 256^2) = 1 TiB.
  const double sats = 65536.0 * 65536.0 * 64 * 4;
  const auto e = estimate_bake_memory(in);
  EXPECT_GE(e.peak_bytes, sats);
  EXPECT_LT(e.peak_bytes, 1.1 * sats);
  EXPECT_EQ(e.stages[e.peak_stage].stage, "tables");

  auto c = input(256);
  c.bake.radiance_dirs = 256;
  c.bake.clusters = 64;
  // The compress stage's directional vectors: 4 bytes per texel and bin = 16 GiB.
  const auto ce = estimate_bake_memory(c);
  EXPECT_GE(ce.peak_bytes, 65536.0 * 65536.0 * 4);
  EXPECT_EQ(ce.stages[ce.peak_stage].stage, "compress");
}

TEST(MemoryEstimate, ListsOnlyTheStagesThatRun) {
  auto in = input(256);
  in.stages = {"load_fabric", "fabric_records", "parallax", "write"};
  const auto e = estimate_bake_memory(in);
  ASSERT_EQ(e.stages.size(), 4u);
  EXPECT_EQ(e.stages[2].stage, "parallax");
  EXPECT_EQ(e.stages[e.peak_stage].stage, "parallax");
  EXPECT_LT(e.peak_bytes, estimate_bake_memory(input(256)).peak_bytes);
}

TEST(MemoryEstimate, RefusalNamesTheKeysAndBothSizes) {
  auto in = raw_tables(input(256));
  in.bake.radiance_dirs = 256;
  in.bake.clusters = 64;
  const auto e = estimate_bake_memory(in);
  EXPECT_NO_THROW(stages::check_memory_estimate(e, in.bake, 2 * e.peak_bytes, "f.toml"));
  try {
    stages::check_memory_estimate(e, in.bake, 23.4 * (1u << 30), "f.toml");
    FAIL() << "not refused";
  } catch (const Error& error) {
    EXPECT_EQ(error.code(), ExitCode::Input);
    const std::string m = error.what();
    EXPECT_NE(m.find("f.toml: [bake] resolution = 256, radiance_dirs = 256, clusters = 64 need ~"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("TiB in the tables stage"), std::string::npos) << m;
    EXPECT_NE(m.find("--max-memory is 23.4 GiB"), std::string::npos) << m;
  }
}

TEST(MemoryEstimate, FormatsBytesInBinaryUnits) {
  EXPECT_EQ(stages::format_bytes(100), "100 B");
  EXPECT_EQ(stages::format_bytes(1536), "1.50 KiB");
  EXPECT_EQ(stages::format_bytes(23.4 * (1u << 30)), "23.4 GiB");
  EXPECT_EQ(stages::format_bytes(std::pow(2.0, 40)), "1.00 TiB");
}

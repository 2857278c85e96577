// Compression settings: the fabric's [bake] keys (0 = auto), the bake command's request on top of
// them, and the usage errors for conflicting options (compress/compress_settings.hpp).
#include <gtest/gtest.h>

#include <string>

#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "compress/cpca.hpp"
#include "fabric/fabric.hpp"

namespace {

using namespace clothbake;
using compress::CompressRequest;
using compress::CompressSettings;

// The message of the Error(Usage) that check_compress_request throws, or "" if it does not.
std::string usage_error(const CompressRequest& r) {
  try {
    compress::check_compress_request(r);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Usage) << e.what();
    return e.what();
  }
  return "";
}

TEST(CompressSettings, FabricZeroMeansTargetMode) {
  BakeSettings b;  // defaults: compress_clusters = compress_rank = 0
  CompressSettings s = compress::settings_from_bake(b);
  EXPECT_TRUE(s.enabled);
  EXPECT_FALSE(s.keep_raw);
  EXPECT_FALSE(s.fixed);
  EXPECT_EQ(s.clusters, 1);
  EXPECT_EQ(s.rank, compress::kDefaultRankCap);
  EXPECT_EQ(s.max_error, compress::kDefaultMaxError);
  EXPECT_EQ(s.cpca().target_error, compress::kDefaultMaxError);

  b.compress_clusters = 3;  // clusters alone: still target mode, with 3 C-PCA clusters
  s = compress::settings_from_bake(b);
  EXPECT_FALSE(s.fixed);
  EXPECT_EQ(s.clusters, 3);

  b.compress_rank = 12;  // an explicit rank: the fixed shape
  s = compress::settings_from_bake(b);
  EXPECT_TRUE(s.fixed);
  EXPECT_EQ(s.clusters, 3);
  EXPECT_EQ(s.rank, 12);
  EXPECT_EQ(s.cpca().target_error, 0.0);

  b.compress_clusters = 0;
  s = compress::settings_from_bake(b);
  EXPECT_TRUE(s.fixed);
  EXPECT_EQ(s.clusters, 1);

  b.compress = false;
  EXPECT_FALSE(compress::settings_from_bake(b).enabled);
}

TEST(CompressSettings, RequestOverridesTheFabric) {
  BakeSettings b;
  b.compress_clusters = 2;
  b.compress_rank = 9;
  b.seed = 77;

  CompressRequest none;
  CompressSettings s = compress::resolve_compress_settings(b, none);
  EXPECT_TRUE(s.fixed);
  EXPECT_EQ(s.rank, 9);
  EXPECT_EQ(s.seed, 77u);

  CompressRequest shape;
  shape.clusters = 4;
  shape.rank = 10;
  s = compress::resolve_compress_settings(b, shape);
  EXPECT_TRUE(s.fixed);
  EXPECT_EQ(s.clusters, 4);
  EXPECT_EQ(s.rank, 10);

  CompressRequest target;
  target.max_error = 0.02;
  s = compress::resolve_compress_settings(b, target);
  EXPECT_FALSE(s.fixed);
  EXPECT_EQ(s.max_error, 0.02);
  EXPECT_EQ(s.clusters, 2) << "the fabric's C-PCA clusters are kept";
  EXPECT_EQ(s.rank, compress::kDefaultRankCap) << "the fabric's fixed rank becomes the cap";

  CompressRequest raw;
  raw.keep_raw = true;
  s = compress::resolve_compress_settings(b, raw);
  EXPECT_TRUE(s.enabled);
  EXPECT_TRUE(s.keep_raw);

  CompressRequest off;
  off.disable = true;
  EXPECT_FALSE(compress::resolve_compress_settings(b, off).enabled);

  // --compress switches on what the fabric switched off; --keep-raw alone does not.
  b.compress = false;
  EXPECT_TRUE(compress::resolve_compress_settings(b, shape).enabled);
  EXPECT_TRUE(compress::resolve_compress_settings(b, target).enabled);
  EXPECT_FALSE(compress::resolve_compress_settings(b, raw).enabled);
}

TEST(CompressSettings, ConflictingOptionsAreUsageErrors) {
  CompressRequest r;
  EXPECT_EQ(usage_error(r), "");
  r.disable = true;
  EXPECT_EQ(usage_error(r), "");
  r.keep_raw = true;
  std::string m = usage_error(r);
  EXPECT_NE(m.find("--no-compress"), std::string::npos) << m;
  EXPECT_NE(m.find("--keep-raw"), std::string::npos) << m;
  r.keep_raw = false;
  r.max_error = 0.01;
  m = usage_error(r);
  EXPECT_NE(m.find("--max-error"), std::string::npos) << m;
  r = {};
  r.clusters = 1;
  r.rank = 8;
  r.max_error = 0.01;
  m = usage_error(r);
  EXPECT_NE(m.find("--compress conflicts with --max-error"), std::string::npos) << m;
  r = {};
  r.clusters = 1;
  r.rank = 8;
  r.keep_raw = true;
  EXPECT_EQ(usage_error(r), "");  // a fixed shape, raw kept: fine
  for (double bad : {0.0, -0.1, 1.5}) {
    r = {};
    r.max_error = bad;
    m = usage_error(r);
    EXPECT_NE(m.find("--max-error expects"), std::string::npos) << bad << ": " << m;
  }
  r = {};
  r.max_error = 1.0;
  EXPECT_EQ(usage_error(r), "");
}

TEST(CompressSettings, GivenNamesTheOptionsInCommandLineSpelling) {
  CompressRequest r;
  EXPECT_TRUE(r.given().empty());
  r.keep_raw = true;
  r.max_error = 0.01;
  EXPECT_EQ(r.given(), (std::vector<std::string>{"--max-error", "--keep-raw"}));
}

}  // namespace

// Compression into sections and the reader's compressed tables: queries are exact (to rounding)
// against direct sums of the decompressed texels for any footprint (fractional corners, negative
// coordinates, many tiles, the far corner), agree with query(), texel_value and decompress_texels,
// the int64 path for N > 256, determinism, and the stiff cases.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "common/error.hpp"
#include "model/splitmix64.hpp"
#include "tests/support/compress_test_util.hpp"

namespace clothbake::compress {
namespace {

using test::direct_sums;

void expect_queries_exact(const reader::CompressedRadianceTables& tables,
                          const std::vector<float>& decoded, const std::vector<uint8_t>& cluster,
                          int n, int bins_per_side, int clusters, uint64_t seed) {
  model::SplitMix64 rng(seed);
  std::vector<reader::Footprint> rects = {
      {double(n - 1), double(n - 1), double(n), double(n)},  // far corner texel
      {0, 0, double(n), double(n)},                          // one tile
      {-3.25, -7.5, -1.0, 2.75},                             // negative coordinates
      {2.5, 1.25, 2.5 + 2.5 * n, 1.25 + 3.0 * n + 0.5},      // many tiles
      {5.0, 5.0, 5.0, 9.0},                                  // empty
  };
  for (int i = 0; i < 60; ++i) {
    const double x0 = (rng.uniform() - 0.3) * 2 * n, y0 = (rng.uniform() - 0.3) * 2 * n;
    const double w = rng.uniform() * (i % 3 == 0 ? 3 * n : 6),
                 h = rng.uniform() * (i % 3 == 0 ? 2 * n : 6);
    rects.push_back({x0, y0, x0 + w, y0 + h});
  }
  for (std::size_t i = 0; i < rects.size(); ++i) {
    const double phi = 6.283 * rng.uniform(), ct = rng.uniform() * 2 - 1;
    const double hv[3] = {std::sqrt(1 - ct * ct) * std::cos(phi),
                          std::sqrt(1 - ct * ct) * std::sin(phi), ct};
    const auto want = direct_sums(decoded, cluster, n, bins_per_side, clusters, rects[i], hv);
    std::vector<double> got(std::size_t(clusters), -1.0);
    ASSERT_TRUE(tables.query_all(rects[i], hv, got.data()).ok());
    double scale = 1e-30;
    for (double v : want)
      scale = std::max(scale, std::fabs(v));
    for (int c = 0; c < clusters; ++c) {
      EXPECT_NEAR(got[std::size_t(c)], want[std::size_t(c)], 2e-6 * scale + 1e-9)
          << "footprint " << i << " cluster " << c;
      double one = -1;
      ASSERT_TRUE(tables.query(rects[i], hv, uint32_t(c), &one).ok());
      EXPECT_EQ(one, got[std::size_t(c)]);  // the same arithmetic on the cluster's images
      EXPECT_TRUE(tables.try_query(rects[i], hv, uint32_t(c), &one));
    }
  }
}

TEST(CompressedTables, QueriesMatchDirectSumsOfTheDecompressedTexels) {
  const DirectionalTexels data = test::synthetic_texels(24, 4, 3, 1);
  CpcaOptions o;
  o.clusters_per_stratum = 2;
  o.rank = 3;
  CompressionStats stats;
  const CompressedTableSet set = compress_tables(data, o, &stats);
  EXPECT_GT(stats.cells, 3);
  EXPECT_GT(stats.error, 0.0);  // lossy at rank 3
  EXPECT_LT(stats.error, 0.2);
  const auto asset = test::memory_asset(compressed_sections(set));
  reader::CompressedRadianceTables tables;
  ASSERT_TRUE(tables.open(asset->asset, reader::RadianceTableKind::Specular).ok());
  EXPECT_EQ(tables.resolution(), 24u);
  EXPECT_EQ(tables.cluster_count(), 3u);
  const std::vector<float> decoded = decompress_texels(set);
  // Texel decoding agrees with decompress_texels; texels without a cell are 0 and clusterless.
  for (uint32_t y = 0; y < 24; ++y)
    for (uint32_t x = 0; x < 24; ++x) {
      const std::size_t t = y * 24 + x;
      EXPECT_EQ(tables.cluster_of_texel(x, y), data.cluster[t] == 255 ? -1 : int(data.cluster[t]));
      for (uint32_t b = 0; b < 16; b += 5)
        EXPECT_NEAR(tables.texel_value(b, x, y), decoded[t * 16 + b],
                    1e-5 * (1 + std::fabs(decoded[t * 16 + b])));
    }
  // The measured error is the error of what is stored.
  double e2 = 0, s2 = 0;
  for (std::size_t i = 0; i < decoded.size(); ++i) {
    e2 += (double(decoded[i]) - data.values[i]) * (double(decoded[i]) - data.values[i]);
    s2 += double(data.values[i]) * data.values[i];
  }
  EXPECT_NEAR(stats.error, std::sqrt(e2 / s2), 1e-6);
  expect_queries_exact(tables, decoded, data.cluster, 24, 4, 3, 5);
}

TEST(CompressedTables, LowRankDataIsStoredToQuantisationPrecision) {
  // Per cluster, every texel's vector is a + s(x) b: affine rank 1.
  DirectionalTexels d = test::synthetic_texels(20, 3, 2, 0);
  for (std::size_t t = 0; t < d.texels(); ++t)
    for (int b = 0; b < 9; ++b)
      d.values[t * 9 + std::size_t(b)] =
          d.cluster[t] == 255 ? 0.0f
                              : float(2.0 + d.cluster[t] + 0.2 * std::sin(0.1 * double(t)) * b);
  CpcaOptions o;
  o.rank = 4;
  CompressionStats stats;
  const CompressedTableSet set = compress_tables(d, o, &stats);
  EXPECT_EQ(stats.max_rank, 1);  // numerical rank detected, not the requested 4
  EXPECT_LT(stats.error, 1e-3);  // fp16 basis and int16 coefficients only
}

TEST(CompressedTables, WideSatsBeyond256AndTheGapKind) {
  const DirectionalTexels data = test::synthetic_texels(260, 1, 2, 3);  // one bin: gap kind
  CpcaOptions o;
  o.rank = 2;
  const CompressedTableSet set = compress_tables(data, o);
  const auto asset = test::memory_asset(compressed_sections(set));
  reader::CompressedRadianceTables tables;
  ASSERT_TRUE(tables.open(asset->asset, reader::RadianceTableKind::Gap).ok());
  expect_queries_exact(tables, decompress_texels(set), data.cluster, 260, 1, 2, 9);
}

TEST(CompressedTables, SameBytesForAnyThreadCount) {
  const DirectionalTexels data = test::synthetic_texels(40, 6, 4, 2);
  CpcaOptions o;
  o.clusters_per_stratum = 3;
  o.target_error = 0.01;
  o.rank = 24;
  std::vector<std::byte> one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = formats::serialize_asset(compressed_sections(compress_tables(data, o)));
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = formats::serialize_asset(compressed_sections(compress_tables(data, o)));
  }
  EXPECT_EQ(one, two);
}

TEST(CompressedTables, AllZeroConstantAndOneTexelClusters) {
  DirectionalTexels d = test::synthetic_texels(16, 2, 3, 0);
  // All zero: nothing to store.
  DirectionalTexels zero = d;
  std::fill(zero.values.begin(), zero.values.end(), 0.0f);
  mark_zero_texels(&zero);
  CompressionStats zs;
  const CompressedTableSet empty = compress_tables(zero, CpcaOptions{}, &zs);
  EXPECT_TRUE(empty.empty());
  EXPECT_TRUE(compressed_sections(empty).empty());
  EXPECT_EQ(zs.error, 0.0);
  // Constant: exact with rank 0; cluster 2 reduced to a single texel.
  DirectionalTexels c = d;
  for (std::size_t t = 0; t < c.texels(); ++t) {
    c.cluster[t] = t == 37 ? 2 : uint8_t(t % 2);
    for (int b = 0; b < 4; ++b)
      c.values[t * 4 + std::size_t(b)] = 0.25f;
  }
  CompressionStats cs;
  const CompressedTableSet set = compress_tables(c, CpcaOptions{}, &cs);
  EXPECT_EQ(cs.max_rank, 0);
  EXPECT_EQ(cs.cells, 3);
  EXPECT_LT(cs.error, 1e-6);
  const auto asset = test::memory_asset(compressed_sections(set));
  reader::CompressedRadianceTables tables;
  ASSERT_TRUE(tables.open(asset->asset, reader::RadianceTableKind::Specular).ok());
  const double h[3] = {0.1, 0.2, 0.9};
  double f[3];
  ASSERT_TRUE(tables.query_all({0, 0, 16, 16}, h, f).ok());
  EXPECT_NEAR(f[2], 0.25, 1e-6);  // the one texel of cluster 2
  EXPECT_NEAR(f[0] + f[1] + f[2], 0.25 * 256, 1e-3);
  // NaN or negative values are refused, naming the texel.
  DirectionalTexels bad = d;
  bad.values[5 * 4 + 1] = -1.0f;
  try {
    compress_tables(bad, CpcaOptions{});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("texel (5, 0) bin 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace clothbake::compress

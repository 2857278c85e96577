// Compression of real Integral-Radiance data (an example fabric at a small size): the stored
// error is the measured error, footprint errors shrink with the target, and the stiff case of a
// very narrow lobe (roughness 0.01) gives finite tables and an honest error.
#include <gtest/gtest.h>

#include "bake/inputs/fabric_load.hpp"
#include "tables/radiance_fill.hpp"
#include "tests/support/compress_test_util.hpp"

namespace clothbake::compress {
namespace {

struct SmallFabric {
  Fabric fabric;
  std::vector<uint8_t> labels;
};

SmallFabric load(const char* name, int n) {
  LoadOptions options;
  options.resolution = n;
  SmallFabric s;
  s.fabric = load_fabric_description(
                 std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/" + name, options)
                 .fabric;
  // Stand-in visibility clusters: yarn id and tangent hemisphere (4 clusters).
  const auto& m = s.fabric.maps;
  for (std::size_t t = 0; t < m.texel_count(); ++t)
    s.labels.push_back(uint8_t(2 * (m.yarn_id[t] % 2) + (m.tangent[t][2] > 0 ? 1 : 0)));
  return s;
}

double footprint_rms(const DirectionalTexels& data, const CompressedTableSet& set, int side) {
  const auto asset = test::memory_asset(compressed_sections(set));
  reader::CompressedRadianceTables tables;
  EXPECT_TRUE(tables.open(asset->asset, data.kind).ok());
  double e2 = 0, s2 = 0;
  const int n = data.resolution;
  for (int i = 0; i < 200; ++i) {
    const double x0 = (i * 7919) % (n * 8) / 8.0, y0 = (i * 104729) % (n * 8) / 8.0;
    const double ct = 0.05 + 0.9 * ((i * 37) % 100) / 100.0, phi = 0.0628 * i;
    const double h[3] = {std::sqrt(1 - ct * ct) * std::cos(phi),
                         std::sqrt(1 - ct * ct) * std::sin(phi), ct};
    const reader::Footprint r{x0, y0, x0 + side, y0 + side};
    const auto want = test::direct_sums(data.values, data.cluster, n, data.bins_per_side,
                                        data.cluster_count, r, h);
    std::vector<double> got(std::size_t(data.cluster_count));
    EXPECT_TRUE(tables.query_all(r, h, got.data()).ok());
    for (std::size_t c = 0; c < got.size(); ++c) {
      EXPECT_TRUE(std::isfinite(got[c]));
      e2 += (got[c] - want[c]) * (got[c] - want[c]);
      s2 += want[c] * want[c];
    }
  }
  return std::sqrt(e2 / s2);
}

TEST(FabricCompression, TwillErrorFollowsTheTarget) {
  const SmallFabric s = load("twill.toml", 32);
  const auto in = tables::radiance_inputs(s.fabric, s.labels, 4);
  const DirectionalTexels data =
      directional_texels(reader::RadianceTableKind::Specular, in.view, 12);
  double previous = 1e9;
  for (double target : {0.1, 0.03, 0.01}) {
    CpcaOptions o;
    o.rank = 64;
    o.target_error = target;
    CompressionStats stats;
    const CompressedTableSet set = compress_tables(data, o, &stats);
    EXPECT_LE(stats.cpca_error, target * 1.0001);
    EXPECT_LE(stats.error, target * 1.05);  // quantisation adds little
    const double rms4 = footprint_rms(data, set, 4);
    EXPECT_LT(rms4, previous);
    EXPECT_LT(rms4, 2 * target) << target;
    previous = rms4;
    EXPECT_GT(stats.ratio(), 10.0);
  }
}

TEST(FabricCompression, VeryNarrowLobesStayFiniteAndReportTheirError) {
  SmallFabric s = load("satin.toml", 32);
  for (auto& yarn : s.fabric.yarns)
    yarn.roughness = 0.01;
  const auto in = tables::radiance_inputs(s.fabric, s.labels, 4);
  const DirectionalTexels data =
      directional_texels(reader::RadianceTableKind::Specular, in.view, 16);
  CpcaOptions o;
  o.rank = 4;  // far too low for such lobes: the error must say so
  o.target_error = 0.01;
  CompressionStats stats;
  const CompressedTableSet set = compress_tables(data, o, &stats);
  for (float v : decompress_texels(set))
    ASSERT_TRUE(std::isfinite(v));
  EXPECT_GT(stats.error, 0.01);
  EXPECT_TRUE(std::isfinite(stats.error));
  EXPECT_GT(footprint_rms(data, set, 1), 0.01);
}

}  // namespace
}  // namespace clothbake::compress

// The streaming table fill (tables::QuantisedRadianceFill) against the raw fixed-point SATs: the
// per-texel vectors C-PCA compresses are the same bits whichever way they are made, for 32- and
// 64-bit elements, both table kinds and a label map with an empty cluster.
#include <gtest/gtest.h>

#include <cstring>

#include "bake/inputs/fabric_load.hpp"
#include "compress/directional_texels.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::compress {
namespace {

struct Case {
  Fabric fabric;
  std::vector<uint8_t> labels;
};

Case twill_with_gaps(int n) {
  LoadOptions options;
  options.resolution = n;
  Case c;
  c.fabric = load_fabric_description(
                 std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/twill.toml", options)
                 .fabric;
  auto& m = c.fabric.maps;
  for (std::size_t t = 0; t < m.texel_count(); t += 3)
    m.gap[t] = 0.5f * float(t % 3 == 0) * float(t % 2);  // some texels half and fully open
  // Clusters 0, 1 and 3 of 4 (cluster 2 is empty: no table column for it).
  for (std::size_t t = 0; t < m.texel_count(); ++t)
    c.labels.push_back(m.tangent[t][2] > 0 ? uint8_t(m.yarn_id[t] % 2) : uint8_t(3));
  return c;
}

void expect_same(const DirectionalTexels& a, const DirectionalTexels& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.resolution, b.resolution);
  EXPECT_EQ(a.bins_per_side, b.bins_per_side);
  EXPECT_EQ(a.cluster_count, b.cluster_count);
  EXPECT_EQ(a.samples_per_bin_side, b.samples_per_bin_side);
  EXPECT_EQ(a.lobes, b.lobes);
  EXPECT_EQ(a.min_roughness, b.min_roughness);
  EXPECT_EQ(a.cluster, b.cluster);
  ASSERT_EQ(a.values.size(), b.values.size());
  EXPECT_EQ(std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)), 0);
}

TEST(StreamedFill, EqualsTheRawSatsBitForBit) {
  const Case c = twill_with_gaps(24);
  const auto in = tables::radiance_inputs(c.fabric, c.labels, 4);
  for (const double precision : {1e-5, 1e-12}) {  // u32 and u64 elements
    tables::RadianceOptions options;
    options.bins_per_side = 6;
    options.max_relative_error = precision;
    options.warn_unresolved = false;
    const std::vector<tables::RadianceTableSet> sets =
        tables::build_radiance_tables(in.view, options);
    ASSERT_EQ(sets.size(), 2u);
    for (const auto& set : sets) {
      const tables::QuantisedRadianceFill fill(set.kind(), in.view, options);
      EXPECT_EQ(fill.header().info.element_bits, set.info.element_bits);
      EXPECT_EQ(fill.header().clusters, set.clusters);
      EXPECT_EQ(fill.raw_sat_bytes(), set.sat.size());
      EXPECT_EQ(std::memcmp(&fill.header().info, &set.info, sizeof set.info), 0);
      const auto sections = tables::radiance_sections(tables::RadianceTableSet(set));
      const auto view = tables::find_radiance_sections(sections, set.kind());
      SCOPED_TRACE(std::string(reader::radiance_kind_name(set.kind())) + " bits " +
                   std::to_string(set.info.element_bits));
      expect_same(directional_texels(fill), directional_texels(view, c.labels));
    }
  }
}

// A fill with nothing to store (no texel with I(x) < 1: no gap table) gives only zeros.
TEST(StreamedFill, EmptyKindIsAllZero) {
  Case c = twill_with_gaps(8);
  for (auto& g : c.fabric.maps.gap)
    g = 1.0f;
  const auto in = tables::radiance_inputs(c.fabric, c.labels, 4);
  const tables::QuantisedRadianceFill fill(reader::RadianceTableKind::Gap, in.view, {});
  EXPECT_TRUE(fill.empty());
  const DirectionalTexels data = directional_texels(fill);
  for (float v : data.values)
    EXPECT_EQ(v, 0.0f);
  for (uint8_t k : data.cluster)
    EXPECT_EQ(k, kNoStratum);
}

}  // namespace
}  // namespace clothbake::compress

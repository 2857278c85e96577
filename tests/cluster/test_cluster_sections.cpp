// Visibility cluster sections: written by cluster/cluster_sections.hpp, read back through the
// reader library (formats/reader/cluster_sections.hpp), including bilinear mean-visibility
// lookups and hostile label maps.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cluster/cluster_sections.hpp"
#include "formats/reader/cluster_sections.hpp"
#include "model/directions.hpp"

using namespace clothbake;

namespace {

cluster::VisibilityClusters make_clusters(int n, int k, int dirs) {
  cluster::VisibilityClusters c;
  c.resolution = n;
  c.clusters = k;
  c.visibility_dirs = dirs;
  for (int i = 0; i < n * n; ++i)
    c.labels.push_back(uint8_t(i % k));
  for (int i = 0; i < k * dirs * dirs; ++i)
    c.mean_visibility.push_back(float(i % 97) / 97.0f);
  return c;
}

struct Opened {
  std::vector<std::byte> bytes;
  reader::Asset asset;
};

std::unique_ptr<Opened> open_sections(std::vector<formats::Section> s) {
  auto o = std::make_unique<Opened>();
  o->bytes = formats::serialize_asset(s);
  EXPECT_TRUE(o->asset.open_memory(o->bytes.data(), o->bytes.size()).ok());
  return o;
}

}  // namespace

TEST(ClusterSections, RoundTripAndBilinearLookup) {
  auto c = make_clusters(16, 5, 8);
  auto o = open_sections(cluster::cluster_sections(c));
  reader::VisibilityClusterView v;
  ASSERT_TRUE(v.open(o->asset).ok());
  EXPECT_EQ(v.resolution(), 16u);
  EXPECT_EQ(v.cluster_count(), 5u);
  EXPECT_EQ(v.visibility_dirs(), 8u);
  for (int y = -20; y < 20; y += 3)
    for (int x = -20; x < 20; x += 7) {
      const int xm = ((x % 16) + 16) % 16, ym = ((y % 16) + 16) % 16;
      EXPECT_EQ(v.label(x, y), c.labels[std::size_t(ym * 16 + xm)]);
    }
  model::DirectionGrid<double> grid{8, 0.0};
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      const model::Vec3d d = grid.bin_center(i, j);
      const double w[3] = {d.x, d.y, d.z};
      double m;
      ASSERT_TRUE(v.mean_visibility(3, w, &m).ok());
      EXPECT_NEAR(m, c.mean_visibility[std::size_t(3 * 64 + grid.bin_index(i, j))], 1e-6);
    }
  const double zero[3] = {0, 0, 0}, up[3] = {0, 0, 1};
  double m;
  EXPECT_FALSE(v.mean_visibility(0, zero, &m).ok());
  EXPECT_FALSE(v.mean_visibility(5, up, &m).ok());
}

TEST(ClusterSections, HostileLabelsAndValuesAreRejected) {
  {
    auto c = make_clusters(8, 3, 4);
    c.labels[17] = 3;  // >= C
    auto o = open_sections(cluster::cluster_sections(c));
    reader::VisibilityClusterView v;
    reader::Status st = v.open(o->asset);
    EXPECT_FALSE(st.ok());
    EXPECT_NE(std::string(st.message()).find("texel (1, 2)"), std::string::npos) << st.message();
  }
  {
    auto c = make_clusters(8, 3, 4);
    for (auto& l : c.labels)
      if (l == 2) l = 0;  // cluster 2 without texels
    auto o = open_sections(cluster::cluster_sections(c));
    reader::VisibilityClusterView v;
    EXPECT_FALSE(v.open(o->asset).ok());
  }
  {
    auto c = make_clusters(8, 3, 4);
    c.mean_visibility[5] = 7.0f;
    auto o = open_sections(cluster::cluster_sections(c));
    reader::VisibilityClusterView v;
    EXPECT_FALSE(v.open(o->asset).ok());
  }
  {
    reader::VisibilityClusterView v;
    auto o = open_sections({});
    EXPECT_EQ(v.open(o->asset).code(), reader::ErrorCode::NotFound);
  }
}

// Half-vector bin quadrature and the 2-sigma rule (tables/half_vector_bins.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "common/error.hpp"
#include "model/directions.hpp"
#include "tables/half_vector_bins.hpp"

using namespace clothbake;
using namespace clothbake::tables;

TEST(HalfVectorBins, QuadratureDirectionsAreUnitAndInsideTheirBin) {
  const HalfVectorBins q = make_half_vector_bins(16, 3);
  ASSERT_EQ(q.x.size(), std::size_t(16 * 16 * 9));
  model::DirectionGrid<double> grid{16, 0.0};
  for (int b = 0; b < q.bin_count(); ++b)
    for (int k = b * 9; k < (b + 1) * 9; ++k) {
      model::Vec3d d(q.x[std::size_t(k)], q.y[std::size_t(k)], q.z[std::size_t(k)]);
      ASSERT_NEAR(model::length(d), 1.0, 1e-6);
      ASSERT_GE(d.z, 0.0);
      ASSERT_EQ(grid.bin_of(d), b) << "sample " << k;
    }
}

TEST(HalfVectorBins, TwoSigmaRule) {
  // The paper: 32^2 bins resolve roughness 0.04 (bin width sqrt(2 pi) / 32 = 0.0783 <= 0.08).
  EXPECT_TRUE(bins_resolve_roughness(32, 0.04));
  EXPECT_FALSE(bins_resolve_roughness(32, 0.039));
  EXPECT_EQ(bins_per_side_for_roughness(0.04), 32);
  EXPECT_EQ(bins_per_side_for_roughness(0.01), 126);  // ceil(125.33)
  EXPECT_TRUE(bins_resolve_roughness(126, 0.01));
  EXPECT_FALSE(bins_resolve_roughness(125, 0.01));
  EXPECT_NEAR(bin_angular_width(32), std::sqrt(2 * M_PI) / 32, 1e-15);
  // Quadrature density: sub-cell spacing <= sigma / 2, clamped to [2, 8].
  EXPECT_EQ(default_samples_per_side(32, 0.3), 2);
  EXPECT_EQ(default_samples_per_side(32, 0.04), 4);
  EXPECT_EQ(default_samples_per_side(32, 0.01), 8);
}

// The default bins: the fewest at most sigma / 3 wide, within [32, 128].
TEST(HalfVectorBins, DefaultBinsAreAThirdOfTheNarrowestRoughness) {
  for (double sigma : {0.03, 0.0588, 0.06, 0.07, 0.08, 0.1, 0.2, 0.235, 0.4, 1.0}) {
    const int n = default_bins_per_side(sigma);
    EXPECT_GE(n, 32) << sigma;
    EXPECT_LE(n, 128) << sigma;
    if (n > 32 && n < 128) {
      EXPECT_LE(bin_angular_width(n), sigma / 3 * (1 + 1e-12)) << sigma;
      EXPECT_GT(bin_angular_width(n - 1), sigma / 3) << sigma;
    } else if (n == 32) {
      EXPECT_LE(bin_angular_width(32), sigma / 3 * (1 + 1e-12)) << sigma;
    } else {
      EXPECT_GT(bin_angular_width(127), sigma / 3) << sigma;
    }
  }
  EXPECT_EQ(default_bins_per_side(0.06), 126);  // the example satin
  EXPECT_EQ(default_bins_per_side(0.4), 32);    // the example twill
  EXPECT_EQ(default_bins_per_side(0.0), 128);   // no roughness: the finest
}

TEST(HalfVectorBins, RejectsBadSizes) {
  EXPECT_THROW(make_half_vector_bins(0, 2), Error);
  EXPECT_THROW(make_half_vector_bins(300, 2), Error);
  EXPECT_THROW(make_half_vector_bins(8, 0), Error);
  EXPECT_THROW(make_half_vector_bins(8, 17), Error);
}

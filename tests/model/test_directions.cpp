// The equal-area direction grid shared by every table (model/directions.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "model/directions.hpp"

using clothbake::model::DirectionGrid;
using clothbake::model::Vec3d;

namespace {

Vec3d cross3(const Vec3d& a, const Vec3d& b) {
  return clothbake::model::cross(a, b);
}

class DirectionGridTest : public ::testing::TestWithParam<double> {};

// |d(direction)/du x d(direction)/dv| must equal the cap's solid angle 2 pi (1 - min_cos)
// everywhere (the square has area 1): that is what "uniform in solid angle" means.
TEST_P(DirectionGridTest, JacobianIsConstantSolidAngle) {
  const double min_cos = GetParam();
  DirectionGrid<double> grid{32, min_cos};
  const double expected = 2 * M_PI * (1 - min_cos);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(0.02, 0.98);
  const double h = 1e-6;
  int checked = 0;
  for (int k = 0; k < 20000; ++k) {
    double u = uni(rng), v = uni(rng);
    // Skip the diagonals of the concentric map, where the derivative jumps (the map is continuous).
    double a = 2 * u - 1, b = 2 * v - 1;
    if (std::abs(std::abs(a) - std::abs(b)) < 4 * h) continue;
    Vec3d du = (grid.direction(u + h, v) - grid.direction(u - h, v)) / (2 * h);
    Vec3d dv = (grid.direction(u, v + h) - grid.direction(u, v - h)) / (2 * h);
    double jac = clothbake::model::length(cross3(du, dv));
    ASSERT_NEAR(jac, expected, 1e-4 * expected) << "at u=" << u << " v=" << v;
    ++checked;
  }
  EXPECT_GT(checked, 19000);
}

TEST_P(DirectionGridTest, DirectionsAreUnitAndInsideTheCap) {
  const double min_cos = GetParam();
  DirectionGrid<double> grid{16, min_cos};
  for (int j = 0; j <= 64; ++j)
    for (int i = 0; i <= 64; ++i) {
      Vec3d d = grid.direction(i / 64.0, j / 64.0);
      EXPECT_NEAR(clothbake::model::length(d), 1.0, 1e-12);
      EXPECT_GE(d.z, min_cos - 1e-12);
    }
  // The square's border is the cap's rim.
  EXPECT_NEAR(grid.direction(0.0, 0.3).z, min_cos, 1e-12);
  EXPECT_NEAR(grid.direction(0.5, 0.5).z, 1.0, 1e-12);
}

TEST_P(DirectionGridTest, InverseRoundTrips) {
  const double min_cos = GetParam();
  DirectionGrid<double> grid{32, min_cos};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int k = 0; k < 10000; ++k) {
    double u = uni(rng), v = uni(rng);
    double u2, v2;
    grid.to_square(grid.direction(u, v), u2, v2);
    ASSERT_NEAR(u2, u, 1e-9);
    ASSERT_NEAR(v2, v, 1e-9);
  }
}

// Directions drawn uniformly in solid angle by an independent method (z uniform on [min_cos, 1],
// phi uniform) fall equally into the bins: chi-square test, 1023 degrees of freedom at n = 32.
TEST_P(DirectionGridTest, UniformDirectionsFillBinsEqually) {
  const double min_cos = GetParam();
  DirectionGrid<double> grid{32, min_cos};
  const int samples = 1 << 20;
  std::vector<int> counts(grid.bin_count(), 0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int k = 0; k < samples; ++k) {
    double z = min_cos + (1 - min_cos) * uni(rng);
    double phi = 2 * M_PI * uni(rng);
    double s = std::sqrt(1 - z * z);
    counts[grid.bin_of(Vec3d{s * std::cos(phi), s * std::sin(phi), z})]++;
  }
  const double expected = double(samples) / grid.bin_count();
  double chi2 = 0;
  for (int c : counts)
    chi2 += (c - expected) * (c - expected) / expected;
  const double dof = grid.bin_count() - 1;
  // Wilson-Hilferty: the 1e-6 upper quantile of chi2(dof) is about dof + 4.75 * sqrt(2 dof) + ...
  EXPECT_LT(chi2, dof + 5.0 * std::sqrt(2 * dof)) << "chi2 = " << chi2;
  EXPECT_GT(chi2, dof - 5.0 * std::sqrt(2 * dof)) << "chi2 = " << chi2;
}

TEST_P(DirectionGridTest, BilinearWeightsInterpolateBinCentres) {
  const double min_cos = GetParam();
  DirectionGrid<double> grid{8, min_cos};
  // At a bin centre the lookup returns that bin alone.
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      auto w = grid.bilinear(grid.bin_center(i, j));
      double at_bin = 0, total = 0;
      for (int k = 0; k < 4; ++k) {
        total += w.weight[k];
        if (w.index[k] == grid.bin_index(i, j)) at_bin += w.weight[k];
      }
      EXPECT_NEAR(total, 1.0, 1e-12);
      EXPECT_NEAR(at_bin, 1.0, 1e-9);
    }
  // Between centres, interpolating the square coordinate u of the bin centres reproduces u.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(1.0 / 16, 15.0 / 16);
  for (int k = 0; k < 1000; ++k) {
    double u = uni(rng), v = uni(rng);
    auto w = grid.bilinear(grid.direction(u, v));
    double ui = 0, vi = 0;
    for (int q = 0; q < 4; ++q) {
      int i = w.index[q] % 8, j = w.index[q] / 8;
      ui += w.weight[q] * (i + 0.5) / 8;
      vi += w.weight[q] * (j + 0.5) / 8;
    }
    EXPECT_NEAR(ui, u, 1e-9);
    EXPECT_NEAR(vi, v, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(Caps, DirectionGridTest, ::testing::Values(0.0, 0.6));

TEST(DirectionGrid, BelowTheCapClampsToTheRimAndZeroIsThePole) {
  DirectionGrid<double> grid{32, 0.6};
  double u, v;
  grid.to_square(Vec3d{1, 0, 0.1}, u, v);
  EXPECT_NEAR(grid.direction(u, v).z, 0.6, 1e-12);
  grid.to_square(Vec3d{0, 0, 0}, u, v);
  EXPECT_EQ(u, 0.5);
  EXPECT_EQ(v, 0.5);
  EXPECT_EQ(clothbake::model::fold_to_upper_hemisphere(Vec3d{0, 0.6, -0.8}).z, 0.8);
}

TEST(DirectionGrid, FloatAgreesWithDouble) {
  DirectionGrid<float> gf{32, 0.0f};
  DirectionGrid<double> gd{32, 0.0};
  for (int j = 0; j < 32; ++j)
    for (int i = 0; i < 32; ++i) {
      auto a = gf.bin_center(i, j);
      auto b = gd.bin_center(i, j);
      EXPECT_NEAR(a.x, b.x, 1e-6);
      EXPECT_NEAR(a.y, b.y, 1e-6);
      EXPECT_NEAR(a.z, b.z, 1e-6);
    }
}

}  // namespace

// The atan2-free direction lookup (DirectionGrid::to_square_fast and bilinear_fast) against the
// exact Shirley-Chiu inverse (to_square, through concentric_disk_to_square and atan2): the same
// square point within 1e-8, and the same bins with the same weights within 1e-5, on random
// directions and on every kind of boundary (octant diagonals, axes, pole, rim, below the cap,
// bin centres and bin edges).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "model/directions.hpp"

using clothbake::model::DirectionGrid;
using clothbake::model::quarter_turns_of_atan;
using clothbake::model::Vec3;
using clothbake::model::Vec3d;

namespace {

// The bilinear lookup of directions.hpp evaluated on the exact square point, as a bin -> weight
// map (duplicates merged, zero weights dropped).
template <class T>
std::map<int, double> exact_weights(const DirectionGrid<T>& grid, const Vec3<T>& d) {
  T u, v;
  grid.to_square(d, u, v);
  const int n = grid.n;
  const T fx = std::clamp(u * T(n) - T(0.5), T(0), T(n - 1));
  const T fy = std::clamp(v * T(n) - T(0.5), T(0), T(n - 1));
  const int i0 = std::min(int(fx), n - 1), j0 = std::min(int(fy), n - 1);
  const int i1 = std::min(i0 + 1, n - 1), j1 = std::min(j0 + 1, n - 1);
  const T tx = fx - T(i0), ty = fy - T(j0);
  std::map<int, double> w;
  w[j0 * n + i0] += double((1 - tx) * (1 - ty));
  w[j0 * n + i1] += double(tx * (1 - ty));
  w[j1 * n + i0] += double((1 - tx) * ty);
  w[j1 * n + i1] += double(tx * ty);
  return w;
}

template <class T>
std::map<int, double> fast_weights(const DirectionGrid<T>& grid, const Vec3<T>& d) {
  const auto b = grid.bilinear_fast(d);
  std::map<int, double> w;
  for (int k = 0; k < 4; ++k)
    w[b.index[k]] += double(b.weight[k]);
  return w;
}

// Bins whose weights differ by more than tol (a bin missing from one side has weight 0 there).
double max_weight_difference(const std::map<int, double>& a, const std::map<int, double>& b) {
  double worst = 0;
  for (const auto& [bin, w] : a) {
    const auto it = b.find(bin);
    worst = std::max(worst, std::abs(w - (it == b.end() ? 0.0 : it->second)));
  }
  for (const auto& [bin, w] : b)
    if (a.find(bin) == a.end()) worst = std::max(worst, std::abs(w));
  return worst;
}

std::vector<Vec3d> boundary_directions(const DirectionGrid<double>& grid) {
  std::vector<Vec3d> out;
  const double eps[] = {0.0, 1e-300, 1e-12, -1e-12, 1e-7};
  // Octant diagonals and axes at several polar angles, exactly on and just beside them.
  for (double z : {1.0, 0.999999, 0.9, 0.61, 0.6, 0.3, 1e-9, 0.0, -0.2, -1.0})
    for (int k = 0; k < 8; ++k)
      for (double e : eps) {
        const double phi = k * M_PI / 4 + e;
        const double s = std::sqrt(std::max(0.0, 1 - z * z));
        out.push_back({s * std::cos(phi), s * std::sin(phi), z});
      }
  // Exact diagonals and axes with integer components (no rounding in the input).
  for (double x : {-1.0, 0.0, 1.0})
    for (double y : {-1.0, 0.0, 1.0})
      for (double z : {0.0, 1.0, 2.0, -1.0})
        out.push_back({x, y, z});
  // Bin centres and bin edges of the grid (u, v on the lines where the bilinear cell changes).
  for (int i = 0; i <= grid.n; ++i)
    for (int j = 0; j <= grid.n; j += 3) {
      out.push_back(grid.direction(double(i) / grid.n, double(j) / grid.n));
      out.push_back(grid.direction((i + 0.5) / grid.n, (j + 0.5) / grid.n));
    }
  return out;
}

TEST(QuarterTurnsOfAtan, MatchesAtanOnTheUnitInterval) {
  double worst = 0;
  for (int k = -100000; k <= 100000; ++k) {
    const double t = k / 100000.0;
    worst = std::max(worst, std::abs(quarter_turns_of_atan(t) - std::atan(t) * 4 / M_PI));
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_EQ(quarter_turns_of_atan(0.0), 0.0);
  EXPECT_NEAR(quarter_turns_of_atan(1.0), 1.0, 1e-8);
  EXPECT_NEAR(quarter_turns_of_atan(-1.0), -1.0, 1e-8);
  // Odd: the two sides of every axis are mirror images.
  for (double t : {0.1, 0.5, 0.99})
    EXPECT_EQ(quarter_turns_of_atan(-t), -quarter_turns_of_atan(t));
}

class FastLookup : public ::testing::TestWithParam<std::tuple<int, double>> {};

TEST_P(FastLookup, RandomDirectionsGiveTheSameSquarePointAndWeights) {
  const auto [n, min_cos] = GetParam();
  const DirectionGrid<double> grid{n, min_cos};
  std::mt19937_64 rng(11 + n);
  std::normal_distribution<double> normal;
  double worst_uv = 0, worst_w = 0;
  for (int k = 0; k < 200000; ++k) {
    const Vec3d d{normal(rng), normal(rng), normal(rng)};
    double u, v, uf, vf;
    grid.to_square(d, u, v);
    grid.to_square_fast(d, uf, vf);
    worst_uv = std::max({worst_uv, std::abs(u - uf), std::abs(v - vf)});
    worst_w =
        std::max(worst_w, max_weight_difference(exact_weights(grid, d), fast_weights(grid, d)));
  }
  EXPECT_LT(worst_uv, 1e-8);
  EXPECT_LT(worst_w, 1e-5);
}

TEST_P(FastLookup, BoundaryDirectionsAreConsistent) {
  const auto [n, min_cos] = GetParam();
  const DirectionGrid<double> grid{n, min_cos};
  for (const Vec3d& d : boundary_directions(grid)) {
    double u, v, uf, vf;
    grid.to_square(d, u, v);
    grid.to_square_fast(d, uf, vf);
    EXPECT_NEAR(u, uf, 1e-8) << d.x << " " << d.y << " " << d.z;
    EXPECT_NEAR(v, vf, 1e-8) << d.x << " " << d.y << " " << d.z;
    EXPECT_LT(max_weight_difference(exact_weights(grid, d), fast_weights(grid, d)), 1e-5)
        << d.x << " " << d.y << " " << d.z;
    const auto b = grid.bilinear_fast(d);
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(b.weight[k], 0.0);
      EXPECT_GE(b.index[k], 0);
      EXPECT_LT(b.index[k], n * n);
      sum += b.weight[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  // Mirror symmetry: (x, y) -> (-x, y) mirrors u about 1/2, exactly as the exact map does.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  for (int k = 0; k < 1000; ++k) {
    const Vec3d d{normal(rng), normal(rng), std::abs(normal(rng))};
    double u1, v1, u2, v2;
    grid.to_square_fast(d, u1, v1);
    grid.to_square_fast(Vec3d{-d.x, d.y, d.z}, u2, v2);
    EXPECT_NEAR(u1, 1 - u2, 1e-15);
    EXPECT_EQ(v1, v2);
  }
  // The zero vector is the pole; non-finite-free huge and tiny vectors stay finite.
  double u, v;
  grid.to_square_fast(Vec3d{0, 0, 0}, u, v);
  EXPECT_EQ(u, 0.5);
  EXPECT_EQ(v, 0.5);
  grid.to_square_fast(Vec3d{1e-300, 1e-300, 1e-300}, u, v);
  EXPECT_TRUE(std::isfinite(u) && std::isfinite(v));
  grid.to_square_fast(Vec3d{1e150, -1e150, 1e150}, u, v);
  EXPECT_TRUE(std::isfinite(u) && std::isfinite(v));
}

INSTANTIATE_TEST_SUITE_P(Grids, FastLookup,
                         ::testing::Combine(::testing::Values(1, 6, 32, 64),
                                            ::testing::Values(0.0, 0.6)));

TEST(FastLookupFloat, AgreesWithTheExactFloatMap) {
  const DirectionGrid<float> grid{32, 0.0f};
  std::mt19937_64 rng(3);
  std::normal_distribution<float> normal;
  double worst_w = 0;
  for (int k = 0; k < 100000; ++k) {
    const Vec3<float> d{normal(rng), normal(rng), normal(rng)};
    worst_w =
        std::max(worst_w, max_weight_difference(exact_weights(grid, d), fast_weights(grid, d)));
  }
  EXPECT_LT(worst_w, 2e-4);  // float rounding of u * 32 (atan2f itself is not exact)
}

}  // namespace

// Exact fixed-point SATs (tables/fixed_point_sat.hpp): integer exactness, the quantisation
// bound for every rectangle, element-width selection, totals within range.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "common/error.hpp"
#include "tables/fixed_point_sat.hpp"

using namespace clothbake;
using namespace clothbake::tables;

namespace {

struct Table {
  int n, columns, bits;
  std::vector<float> values;
  std::vector<int16_t> column;
  std::vector<double> totals, units;
  std::vector<uint64_t> sat;  // widened copy
};

Table make_table(int n, int columns, int bits, uint64_t seed) {
  Table t{n, columns, bits, {}, {}, {}, {}, {}};
  std::mt19937_64 rng(seed);
  std::lognormal_distribution<float> value(0.0f, 2.0f);  // 4 decades of dynamic range
  t.totals.assign(std::size_t(columns), 0.0);
  for (int i = 0; i < n * n; ++i) {
    t.values.push_back(value(rng));
    int16_t c = int16_t(rng() % uint64_t(columns + 1)) - 1;  // some texels in no column
    t.column.push_back(c);
    if (c >= 0) t.totals[std::size_t(c)] += t.values.back();
  }
  t.units.resize(std::size_t(columns));
  std::vector<std::byte> raw(std::size_t(n) * n * columns * (bits / 8));
  build_fixed_point_sat(n, t.values, t.column, t.totals, bits, t.units.data(), raw.data());
  t.sat.resize(std::size_t(n) * n * columns);
  for (std::size_t i = 0; i < t.sat.size(); ++i) {
    if (bits == 32) {
      uint32_t v;
      std::memcpy(&v, raw.data() + 4 * i, 4);
      t.sat[i] = v;
    } else {
      std::memcpy(&t.sat[i], raw.data() + 8 * i, 8);
    }
  }
  return t;
}

// Exclusive SAT S(i, j), i, j in [0, n].
uint64_t S(const Table& t, int i, int j, int k) {
  if (i == 0 || j == 0) return 0;
  return t.sat[(std::size_t(j - 1) * t.n + std::size_t(i - 1)) * t.columns + std::size_t(k)];
}

}  // namespace

TEST(FixedPointSat, TexelIntegersAreTheRoundedValues) {
  for (int bits : {32, 64}) {
    Table t = make_table(37, 3, bits, 1);
    for (int y = 0; y < t.n; ++y)
      for (int x = 0; x < t.n; ++x)
        for (int k = 0; k < t.columns; ++k) {
          const uint64_t q =
              S(t, x + 1, y + 1, k) - S(t, x, y + 1, k) - S(t, x + 1, y, k) + S(t, x, y, k);
          const std::size_t i = std::size_t(y) * t.n + std::size_t(x);
          // q is the value rounded to the nearest integer step (up to the double rounding of the
          // scaled value itself, 1e-16 relative).
          const double scaled =
              t.column[i] == k ? double(t.values[i]) / t.units[std::size_t(k)] : 0.0;
          ASSERT_LE(std::abs(double(q) - scaled), 0.5 + 1e-15 * scaled)
              << "bits " << bits << " texel " << x << "," << y << " col " << k;
          if (t.column[i] != k) {
            ASSERT_EQ(q, 0u);
          }
        }
  }
}

TEST(FixedPointSat, EveryRectangleWithinTheQuantisationBound) {
  for (int bits : {32, 64}) {
    Table t = make_table(48, 2, bits, 2);
    std::mt19937_64 rng(3);
    for (int trial = 0; trial < 3000; ++trial) {
      int x0 = int(rng() % 48), x1 = int(rng() % 48), y0 = int(rng() % 48), y1 = int(rng() % 48);
      if (x0 > x1) std::swap(x0, x1);
      if (y0 > y1) std::swap(y0, y1);
      ++x1;
      ++y1;
      const int k = int(rng() % 2);
      double direct = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const std::size_t i = std::size_t(y) * 48 + std::size_t(x);
          if (t.column[i] == k) direct += t.values[i];
        }
      const int64_t q =
          int64_t(S(t, x1, y1, k) - S(t, x0, y1, k) - S(t, x1, y0, k) + S(t, x0, y0, k));
      const double area = double(x1 - x0) * (y1 - y0);
      const double unit = t.units[std::size_t(k)];
      ASSERT_LE(std::abs(double(q) * unit - direct),
                0.5 * area * unit * (1 + 1e-9) + 1e-12 * direct)
          << "bits " << bits << " rect " << x0 << "," << y0 << " " << x1 << "," << y1;
    }
  }
}

TEST(FixedPointSat, TotalsStayInRangeAndBoundsAreAsDocumented) {
  Table t = make_table(64, 4, 32, 4);
  for (int k = 0; k < 4; ++k)
    EXPECT_LT(S(t, 64, 64, k), uint64_t(1) << 32);
  // Mean-relative bound N^2 / (2 (2^32 - 1 - N^2)): 7.63e-6 at 256^2 (u32 meets 1e-5), u64 beyond.
  EXPECT_NEAR(sat_relative_error_bound(256, 32), 7.63e-6, 0.01e-6);
  EXPECT_EQ(sat_element_bits(256, 1e-5), 32);
  EXPECT_EQ(sat_element_bits(512, 1e-5), 64);
  EXPECT_EQ(sat_element_bits(512, 1e-4), 32);
  EXPECT_EQ(sat_element_bits(2048, 1e-4), 64);
  EXPECT_LT(sat_relative_error_bound(2048, 64), 1e-11);
}

TEST(FixedPointSat, RejectsAZeroColumnTotal) {
  std::vector<float> v(4, 0.0f);
  std::vector<int16_t> col(4, 0);
  std::vector<double> totals = {0.0}, units(1);
  std::vector<uint32_t> out(4);
  EXPECT_THROW(build_fixed_point_sat(2, v, col, totals, 32, units.data(), out.data()), Error);
}

// Parallax offset of Eq. 2 and the tile-wrap helpers (model/parallax.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "model/parallax.hpp"

namespace {

namespace m = clothbake::model;
using m::TexelPoint;
using m::Vec3d;

TEST(Parallax, OffsetFollowsEquationTwo) {
  const Vec3d o = m::normalize(Vec3d{0.3, -0.4, 0.8});
  const double r = 0.05;
  const auto p = m::parallax_offset(TexelPoint<double>{0.25, 0.5}, o, r);
  EXPECT_NEAR(p.u, 0.25 + r / o.z * o.x, 1e-15);
  EXPECT_NEAR(p.v, 0.5 + r / o.z * o.y, 1e-15);
  // Straight down the normal: no offset; zero depth: no offset.
  const auto q = m::parallax_offset(TexelPoint<double>{0.1, 0.2}, Vec3d{0, 0, 1}, 0.3);
  EXPECT_EQ(q.u, 0.1);
  EXPECT_EQ(q.v, 0.2);
  const auto z = m::parallax_offset(TexelPoint<double>{0.1, 0.2}, o, 0.0);
  EXPECT_EQ(z.u, 0.1);
  // The offset grows as tan(theta): at 60 degrees, r * sqrt(3) along the azimuth.
  const Vec3d o60{std::sqrt(3.0) / 2, 0, 0.5};
  EXPECT_NEAR(m::parallax_offset(TexelPoint<double>{0, 0}, o60, 0.1).u, 0.1 * std::sqrt(3.0),
              1e-15);
}

TEST(Parallax, BelowTheSurfaceOrNonFiniteLeavesThePointUnchanged) {
  const TexelPoint<double> p{0.4, 0.6};
  for (Vec3d o : {Vec3d{1, 0, 0}, Vec3d{0.6, 0, -0.8}}) {
    const auto q = m::parallax_offset(p, o, 0.2);
    EXPECT_EQ(q.u, p.u);
    EXPECT_EQ(q.v, p.v);
  }
  const auto q = m::parallax_offset(p, Vec3d{1, 0, 1e-320}, 0.2);  // offset overflows
  EXPECT_EQ(q.u, p.u);
  const auto n =
      m::parallax_offset(p, Vec3d{0.6, 0, 0.8}, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(n.u, p.u);
}

TEST(Parallax, WrapIntoTheTile) {
  EXPECT_EQ(m::wrap_tile(0.25), 0.25);
  EXPECT_EQ(m::wrap_tile(1.25), 0.25);
  EXPECT_EQ(m::wrap_tile(-0.75), 0.25);
  EXPECT_EQ(m::wrap_tile(1.0), 0.0);
  EXPECT_EQ(m::wrap_tile(-3.0), 0.0);
  // A tiny negative coordinate would round to exactly 1: it wraps to 0 instead.
  EXPECT_LT(m::wrap_tile(-1e-20), 1.0);
  EXPECT_LT(m::wrap_tile(-1e-20f), 1.0f);
  EXPECT_EQ(m::wrap_tile(std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_EQ(m::wrap_tile(std::numeric_limits<double>::quiet_NaN()), 0.0);
  for (double u = -5; u < 5; u += 0.0137) {
    const double w = m::wrap_tile(u);
    ASSERT_GE(w, 0.0);
    ASSERT_LT(w, 1.0);
    ASSERT_NEAR(std::remainder(w - u, 1.0), 0.0, 1e-12);
  }
  EXPECT_EQ(m::wrap_texel(-1, 256), 255);
  EXPECT_EQ(m::wrap_texel(256, 256), 0);
  EXPECT_EQ(m::wrap_texel(-513, 256), 255);
  int x, y;
  m::texel_of(TexelPoint<double>{1.5, -0.001}, 4, x, y);
  EXPECT_EQ(x, 2);
  EXPECT_EQ(y, 3);
}

}  // namespace

// The periodic height field in Embree (raycast/heightfield_scene.hpp) against independent
// reference ray casts: a flat plane in closed form, 1-D profiles exactly, 2-D fields by brute
// force; rays that cross many tiles (segments) for several neighbourhood sizes.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

#include "common/error.hpp"
#include "raycast/heightfield_scene.hpp"
#include "tests/raycast/reference.hpp"

using namespace clothbake;
using namespace clothbake::raycast;
using rctest::kNoHit;
using rctest::Profile;

namespace {

Vec3d random_down(std::mt19937_64& rng, double min_cos) {
  std::uniform_real_distribution<double> uni(0, 1);
  double z = min_cos + (1 - min_cos) * uni(rng);
  double phi = 2 * M_PI * uni(rng);
  double s = std::sqrt(1 - z * z);
  return {s * std::cos(phi), s * std::sin(phi), -z};
}

std::vector<float> heights_from_profile(const Profile& p) {
  const int n = int(p.h.size());
  std::vector<float> h(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      h[std::size_t(y) * n + x] = float(p.h[std::size_t(x)]);
  return h;
}

Profile random_profile(int n, double range, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0, range);
  Profile p;
  for (int i = 0; i < n; ++i)
    p.h.push_back(double(float(uni(rng))));
  return p;
}

}  // namespace

TEST(HeightFieldScene, FlatPlaneIsHitAtItsHeight) {
  std::vector<float> h(64, 0.25f);
  for (int rings : {0, 1, 2}) {
    PeriodicHeightField field(h, 8, rings);
    EXPECT_EQ(field.z_min(), 0.25);
    EXPECT_EQ(field.z_max(), 0.25);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> uni(-3, 3);
    for (int k = 0; k < 2000; ++k) {
      Vec3d o{uni(rng), uni(rng), 1.0};
      Vec3d d = random_down(rng, 0.05);  // down to 87 degrees: up to ~15 tiles sideways
      double expected = 0.75 / -d.z;
      SurfaceHit hit = field.first_hit(o, d, 100.0);
      ASSERT_TRUE(hit.hit) << "rings " << rings << " ray " << k;
      ASSERT_NEAR(hit.t, expected, 1e-5 * expected) << "rings " << rings << " ray " << k;
    }
  }
}

TEST(HeightFieldScene, OneDimensionalProfilesMatchTheExactReference) {
  const int n = 32;
  Profile p = random_profile(n, 0.3, 7);
  std::vector<float> h = heights_from_profile(p);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int rings : {0, 1, 3}) {
    PeriodicHeightField field(h, n, rings);
    RayPacket packet;
    std::array<double, RayPacket::kWidth> t_hit;
    int compared = 0;
    for (int k = 0; k < 4000; ++k) {
      Vec3d o{uni(rng) * 4 - 2, uni(rng) * 4 - 2, 0.31};
      Vec3d d = random_down(rng, 0.1);
      double expected = rctest::first_hit_1d(p, o, d, 10.0);
      SurfaceHit hit = field.first_hit(o, d, 10.0);
      ASSERT_EQ(hit.hit, expected < kNoHit) << "rings " << rings << " ray " << k;
      ASSERT_NEAR(hit.t, expected, 2e-5 * (1 + expected)) << "rings " << rings << " ray " << k;
      // The packet path gives the same answer.
      int lane = k % RayPacket::kWidth;
      packet.ox[lane] = o.x, packet.oy[lane] = o.y, packet.oz[lane] = o.z;
      packet.dx[lane] = d.x, packet.dy[lane] = d.y, packet.dz[lane] = d.z;
      packet.t_max[lane] = 10.0;
      if (lane == RayPacket::kWidth - 1) {
        packet.count = RayPacket::kWidth;
        field.first_hits(packet, t_hit);
        for (int l = 0; l < RayPacket::kWidth; ++l) {
          Vec3d po{packet.ox[l], packet.oy[l], packet.oz[l]};
          Vec3d pd{packet.dx[l], packet.dy[l], packet.dz[l]};
          double ref = rctest::first_hit_1d(p, po, pd, 10.0);
          ASSERT_NEAR(t_hit[l], ref, 2e-5 * (1 + ref));
          ++compared;
        }
      }
    }
    EXPECT_EQ(compared, 4000);
  }
}

TEST(HeightFieldScene, TallFieldsAreExactAcrossManyTiles) {
  // Heights of 5 tile sides and rays down to 80 degrees: up to ~30 tiles sideways, so rays are cut
  // into many segments; every neighbourhood size must give the same, exact answer.
  const int n = 16;
  Profile p = random_profile(n, 5.0, 9);
  std::vector<float> h = heights_from_profile(p);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<PeriodicHeightField*> fields;
  PeriodicHeightField f0(h, n, 0), f1(h, n, 1), f4(h, n, 4);
  for (int k = 0; k < 1500; ++k) {
    Vec3d o{uni(rng), uni(rng), 5.01};
    Vec3d d = random_down(rng, 0.17);
    double expected = rctest::first_hit_1d(p, o, d, 100.0);
    for (PeriodicHeightField* f : {&f0, &f1, &f4}) {
      SurfaceHit hit = f->first_hit(o, d, 100.0);
      ASSERT_TRUE(hit.hit);
      ASSERT_NEAR(hit.t, expected, 1e-5 * (1 + expected)) << "rings " << f->rings() << " ray " << k;
    }
  }
}

TEST(HeightFieldScene, TwoDimensionalFieldsMatchBruteForce) {
  const int n = 8;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<float> h(std::size_t(n) * n);
  for (auto& v : h)
    v = float(0.2 * uni(rng));
  PeriodicHeightField field(h, n, 1);
  int near_edge = 0;
  for (int k = 0; k < 3000; ++k) {
    Vec3d o{uni(rng), uni(rng), 0.21};
    Vec3d d = random_down(rng, 0.3);
    double expected = rctest::first_hit_brute_force(h, n, 2, o, d, 1.0);
    SurfaceHit hit = field.first_hit(o, d, 1.0);
    if (hit.hit && std::abs(hit.t - expected) <= 1e-5) continue;
    // Only rays through an edge may disagree (Embree's test is not watertight).
    ASSERT_TRUE(hit.hit && hit.near_edge)
        << "ray " << k << ": embree " << hit.t << " brute force " << expected;
    ++near_edge;
  }
  EXPECT_LE(near_edge, 3);
}

TEST(HeightFieldScene, HitReportsTheTriangleOfTheInfinitePlane) {
  // A ray straight down onto the centre of quad (2, 5) of tile (-1, 3), lower-right triangle.
  const int n = 8;
  std::vector<float> h(64);
  for (int i = 0; i < 64; ++i)
    h[std::size_t(i)] = float(0.01 * (i % 7));
  PeriodicHeightField field(h, n, 1);
  double qx = 2 - 8, qy = 5 + 24;  // quad index on the infinite grid
  Vec3d o{(qx + 0.5 + 0.3) / n, (qy + 0.5 + 0.1) / n, 1.0};
  SurfaceHit hit = field.first_hit(o, {0, 0, -1}, 2.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.quad_x, long(qx));
  EXPECT_EQ(hit.quad_y, long(qy));
  EXPECT_EQ(hit.triangle, 0);  // below the diagonal: y offset 0.1 < x offset 0.3
}

TEST(HeightFieldScene, RejectsNonFiniteHeightsNamingTheTexel) {
  std::vector<float> h(16, 0.f);
  h[2 * 4 + 3] = std::numeric_limits<float>::quiet_NaN();
  try {
    PeriodicHeightField field(h, 4, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("texel (3, 2)"), std::string::npos) << e.what();
  }
}

// The sideways budget: a ray whose first hit lies beyond the budget answers "no hit" and counts
// as unresolved; one whose hit lies within is unchanged. Rays run along the ridges of a tall
// 1-D sine relief, drifting slowly across them, so that they meet a flank only after 32 to 223
// tiles sideways; budgets around each hit's own sideways distance are tried.
TEST(HeightFieldScene, TheSidewaysBudgetCutsExactlyTheRaysThatGoFurther) {
  const int n = 16;
  std::vector<float> h(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      h[std::size_t(y) * n + x] = float(std::sin(2 * M_PI * (x + 0.5) / n));
  const PeriodicHeightField unlimited(h, n, 1, 1e9);
  EXPECT_EQ(PeriodicHeightField(h, n, 1).max_sideways_tiles(), kMaxSidewaysTiles);
  int checked = 0;
  for (double drift : {0.004, 0.01, 0.03}) {
    // From just above the valley floor (x = 0.75), rising 1/1000 per tile along y.
    const Vec3d origin{0.75, 0.3, -1.0 + 0.01};
    const Vec3d d = model::normalize(Vec3d{drift, 1.0, 0.001});
    const double t_max = 1e4;
    const SurfaceHit hit = unlimited.first_hit(origin, d, t_max);
    ASSERT_TRUE(hit.hit) << drift;
    const double sideways = hit.t * std::hypot(d.x, d.y);
    ASSERT_GT(sideways, 10.0) << "the ray should travel many tiles before the flank";
    for (double budget : {0.5 * sideways, 0.99 * sideways, 1.01 * sideways, 2 * sideways}) {
      const PeriodicHeightField field(h, n, 1, budget);
      const SurfaceHit one = field.first_hit(origin, d, t_max);
      RayPacket packet;
      packet.count = 1;
      packet.ox[0] = origin.x, packet.oy[0] = origin.y, packet.oz[0] = origin.z;
      packet.dx[0] = d.x, packet.dy[0] = d.y, packet.dz[0] = d.z;
      packet.t_max[0] = t_max;
      RayCounters first_counters, occlusion_counters;
      std::array<double, RayPacket::kWidth> t_hit;
      field.first_hits(packet, t_hit, &first_counters);
      std::array<bool, RayPacket::kWidth> occluded;
      field.occluded(packet, occluded, &occlusion_counters);
      const bool within = budget > sideways;
      EXPECT_EQ(one.hit, within) << drift << " " << budget;
      EXPECT_EQ(one.budget_cut, !within);
      EXPECT_EQ(t_hit[0] < 1e300, within);
      EXPECT_EQ(occluded[0], within);
      EXPECT_EQ(first_counters.unresolved.load(), within ? 0u : 1u);
      EXPECT_EQ(occlusion_counters.unresolved.load(), within ? 0u : 1u);
      if (within) {
        EXPECT_NEAR(one.t, hit.t, 1e-9 * hit.t);
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 12);
  EXPECT_THROW(PeriodicHeightField(h, n, 1, 0.0), Error);
}

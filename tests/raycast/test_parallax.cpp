// Parallax tables (raycast/parallax.hpp): closed forms on a flat map and a step, the exact
// 1-D reference on a sine, brute force on isolated spikes, tall fields, thread-count determinism,
// quantisation bound, SATs, bad settings.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "model/directions.hpp"
#include "raycast/heightfield_scene.hpp"
#include "raycast/parallax.hpp"
#include "tests/raycast/reference.hpp"
#include "tests/raycast/synthetic_fields.hpp"

using namespace clothbake;
using namespace clothbake::raycast;
using model::Vec3d;

namespace {

// r of the reference for texel (x, y) and view o: the same ray the bake casts.
double reference_r(const rctest::Profile& p, const ParallaxTable& t, int x, int y, const Vec3d& o) {
  const int n = t.resolution;
  double range = t.depth_scale * 65535.0;
  double lift = std::max(1e-3 * range, 1e-6);
  Vec3d origin{(x + 0.5) / n, (y + 0.5) / n, t.reference_height + lift};
  double hit = rctest::first_hit_1d(p, origin, -o, 100.0);
  return origin.z - hit * o.z - t.reference_height;
}

rctest::Profile profile_of(const FabricMaps& maps) {
  rctest::Profile p;
  for (int x = 0; x < maps.resolution; ++x)
    p.h.push_back(double(maps.height[std::size_t(x)]));
  return p;
}

bool has_warning_containing(const std::vector<std::string>& warnings, const std::string& text) {
  for (const auto& w : warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST(Parallax, FlatMapHasZeroDepthEverywhere) {
  FabricMaps maps = rctest::maps_from(16, [](double, double) { return 0.3; });
  ParallaxTable t = bake_parallax(maps, {});
  EXPECT_EQ(t.depth.size(), 16u * 16u * 32u * 32u);
  EXPECT_EQ(t.reference_height, double(0.3f));
  EXPECT_EQ(t.depth_scale, 0.0);
  EXPECT_EQ(t.stats.rays, 0u);
  for (int dir = 0; dir < 32 * 32; dir += 37)
    for (int x = 0; x < 16; ++x)
      EXPECT_EQ(t.r(dir, x, 3), 0.0);
}

TEST(Parallax, StepFieldMatchesItsClosedForm) {
  // Plateau of height H on texels x < 16, floor 0 on x >= 16 (the mesh ramps between centres).
  const int n = 32;
  const double H = 0.2;
  FabricMaps maps = rctest::maps_from(n, [&](double u, double) { return u < 0.5 ? H : 0.0; });
  ParallaxTable t = bake_parallax(maps, {});
  const double tol = t.depth_scale / 2 + 1e-6;
  EXPECT_EQ(t.reference_height, double(float(H)));
  model::DirectionGrid<double> grid{32, 0.6};
  int floor_checks = 0;
  for (int dir = 0; dir < 32 * 32; ++dir) {
    Vec3d o = grid.bin_center(dir % 32, dir / 32);
    for (int x = 0; x < n; ++x) {
      double r = t.r(dir, x, 5);
      if (x >= 1 && x <= 14) {
        // Plateau interior: the ray starts above the plateau's own vertex.
        ASSERT_NEAR(r, 0.0, tol) << "x " << x << " dir " << dir;
      } else if (x >= 16) {
        // Floor: the ray reaches z = 0 at x_hit = u - H o.x / o.z; if that is strictly between
        // the two ramps (centres 15.5/32 .. 16.5/32 and 31.5/32 .. 32.5/32), r = -H exactly.
        double u = (x + 0.5) / n;
        double x_hit = u - (H + 1e-3 * H) * o.x / o.z;
        if (x_hit > 16.5 / n && x_hit < 31.5 / n) {
          ASSERT_NEAR(r, -H, tol) << "x " << x << " dir " << dir;
          ++floor_checks;
        }
      }
    }
  }
  EXPECT_GT(floor_checks, 5000);
  // Everything else against the exact reference.
  rctest::Profile p = profile_of(maps);
  for (int dir = 0; dir < 32 * 32; ++dir)
    for (int x = 0; x < n; ++x) {
      Vec3d o = grid.bin_center(dir % 32, dir / 32);
      ASSERT_NEAR(t.r(dir, x, 9), reference_r(p, t, x, 9, o), tol + 1e-5)
          << "x " << x << " dir " << dir;
    }
}

TEST(Parallax, SineFieldMatchesTheExactReference) {
  const int n = 64;
  FabricMaps maps =
      rctest::maps_from(n, [](double u, double) { return 0.05 * std::sin(2 * M_PI * 3 * u); });
  ParallaxSettings settings;
  settings.dirs = 16;
  ParallaxTable t = bake_parallax(maps, settings);
  rctest::Profile p = profile_of(maps);
  model::DirectionGrid<double> grid{16, 0.6};
  double worst = 0;
  for (int dir = 0; dir < 16 * 16; ++dir)
    for (int x = 0; x < n; ++x) {
      Vec3d o = grid.bin_center(dir % 16, dir / 16);
      double expected = reference_r(p, t, x, x % n, o);
      worst = std::max(worst, std::abs(t.r(dir, x, x % n) - expected));
    }
  EXPECT_LT(worst, t.depth_scale / 2 + 1e-6);
  EXPECT_LE(t.stats.max_quantization_error, t.depth_scale / 2 * (1 + 1e-9));
  EXPECT_EQ(t.stats.unresolved_rays, 0u);
}

TEST(Parallax, IsolatedSpikesMatchBruteForce) {
  // Three single-texel spikes on a flat floor: most rays pass them and reach the floor.
  const int n = 16;
  FabricMaps maps = rctest::maps_from(n, [](double, double) { return 0.0; });
  maps.height[maps.index(3, 4)] = 0.4f;
  maps.height[maps.index(10, 11)] = 0.25f;
  maps.height[maps.index(15, 0)] = 0.4f;  // on the tile corner: wraps
  ParallaxSettings settings;
  settings.dirs = 8;
  ParallaxTable t = bake_parallax(maps, settings);
  model::DirectionGrid<double> grid{8, 0.6};
  const double range = 0.4, lift = 1e-3 * range;
  int mismatches = 0, spike_hits = 0;
  for (int dir = 0; dir < 64; ++dir)
    for (int y = 0; y < n; ++y)
      for (int x = (y + dir) % 2; x < n; x += 2) {  // half the texels, alternating
        Vec3d o = grid.bin_center(dir % 8, dir / 8);
        Vec3d origin{(x + 0.5) / n, (y + 0.5) / n, double(0.4f) + lift};
        double hit = rctest::first_hit_brute_force(maps.height, n, 1, origin, -o, 10.0);
        double expected = origin.z - hit * o.z - double(0.4f);
        if (expected > -range + 1e-6) ++spike_hits;
        if (std::abs(t.r(dir, x, y) - expected) > t.depth_scale / 2 + 1e-5) ++mismatches;
      }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(spike_hits, 250);  // the spikes are really seen
}

TEST(Parallax, TallHeightsAreExactAndWarn) {
  // Heights of 3 tile sides: offsets reach 4 tiles; rays are cut into segments.
  const int n = 16;
  FabricMaps maps =
      rctest::maps_from(n, [](double u, double) { return 1.5 + 1.5 * std::cos(2 * M_PI * u); });
  take_warnings();
  ParallaxSettings settings;
  settings.dirs = 8;
  settings.rings = 1;  // fewer rings than the 4 tiles of travel: rays are cut into segments
  ParallaxTable t = bake_parallax(maps, settings);
  auto warnings = take_warnings();
  EXPECT_TRUE(has_warning_containing(warnings, "tiles sideways"));
  EXPECT_GT(t.stats.max_sideways, 1.0);
  EXPECT_GT(t.stats.segments, t.stats.rays);
  rctest::Profile p = profile_of(maps);
  model::DirectionGrid<double> grid{8, 0.6};
  for (int dir = 0; dir < 64; ++dir)
    for (int x = 0; x < n; ++x) {
      Vec3d o = grid.bin_center(dir % 8, dir / 8);
      double r = t.r(dir, x, 0);
      ASSERT_TRUE(std::isfinite(r));
      ASSERT_NEAR(r, reference_r(p, t, x, 0, o), t.depth_scale / 2 + 1e-5);
    }
}

TEST(Parallax, OffsetsStayWithinTheCapBound) {
  // Eq. 2 offsets are |r| tan(theta) <= range * tan(theta_cut): 4/3 range for the 0.6 cut. With
  // the cut at 0 (directions to 3 degrees above the horizon) everything stays finite.
  FabricMaps maps = rctest::plain_weave_maps(32);
  for (double min_cos : {0.6, 0.0}) {
    ParallaxSettings settings;
    settings.min_cos = min_cos;
    settings.dirs = 16;
    ParallaxTable t = bake_parallax(maps, settings);
    model::DirectionGrid<double> grid{16, min_cos};
    double range = t.depth_scale * 65535;
    for (int dir = 0; dir < 256; ++dir) {
      Vec3d o = grid.bin_center(dir % 16, dir / 16);
      double tan_theta = std::sqrt(o.x * o.x + o.y * o.y) / o.z;
      for (std::size_t texel = 0; texel < t.texel_count(); texel += 7) {
        double r = t.r(dir, int(texel % 32), int(texel / 32));
        ASSERT_TRUE(std::isfinite(r));
        ASSERT_LE(-r, range * (1 + 1e-9));
        if (min_cos == 0.6) {
          ASSERT_LE(-r * tan_theta, range * 4.0 / 3.0 + 1e-9);
        }
      }
    }
  }
}

TEST(Parallax, SameBytesForAnyThreadCount) {
  FabricMaps maps = rctest::plain_weave_maps(48);  // not a multiple of 16: partial tiles
  ParallaxSettings settings;
  settings.dirs = 8;
  ParallaxTable one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = bake_parallax(maps, settings);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = bake_parallax(maps, settings);
  }
  EXPECT_EQ(one.depth, two.depth);
  EXPECT_EQ(one.depth_scale, two.depth_scale);
  EXPECT_EQ(parallax_sat(one), parallax_sat(two));
}

// The table is exactly what one ray cast through the slow single-ray path (first_hit), encoded
// with std::round, gives: pins the packet path (lanes cast one by one, segments that skip the
// border arithmetic) and the stage's own rounding to the reference encoding, bit for bit, on a
// field whose rays cross the tile border and, with k = 0 and a tall field, need several segments.
TEST(Parallax, CodesEqualSingleRayHitsRoundedToNearest) {
  struct Case {
    FabricMaps maps;
    int rings;
  };
  std::vector<Case> cases;
  cases.push_back({rctest::plain_weave_maps(40), -1});
  cases.push_back({rctest::maps_from(24,
                                     [](double u, double v) {
                                       return 0.8 * std::sin(6.283185307179586 * u) *
                                              std::cos(6.283185307179586 * v);
                                     }),
                   0});
  for (const Case& c : cases) {
    ParallaxSettings settings;
    settings.dirs = 6;
    settings.rings = c.rings;
    testing::internal::CaptureStderr();  // the tall field warns about its offsets
    const ParallaxTable table = bake_parallax(c.maps, settings);
    testing::internal::GetCapturedStderr();
    const int n = c.maps.resolution;
    double z_min = 1e300, z_max = -1e300;
    for (float h : c.maps.height) {
      z_min = std::min(z_min, double(h));
      z_max = std::max(z_max, double(h));
    }
    const double range = z_max - z_min, lift = std::max(1e-3 * range, 1e-6);
    PeriodicHeightField field(c.maps.height, n, table.stats.rings);
    model::DirectionGrid<double> grid{settings.dirs, settings.min_cos};
    std::size_t checked = 0, multi_segment = 0;
    for (int j = 0; j < settings.dirs; ++j)
      for (int i = 0; i < settings.dirs; ++i) {
        const Vec3d o = grid.bin_center(i, j);
        const double t_max = (lift + range + lift) / o.z;
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            const Vec3d origin{(x + 0.5) / n, (y + 0.5) / n, z_max + lift};
            const SurfaceHit hit = field.first_hit(origin, -o, t_max);
            ASSERT_TRUE(hit.hit);
            const double depth = std::clamp(hit.t * o.z - lift, 0.0, range);
            const double code = std::clamp(std::round(depth / table.depth_scale), 0.0, 65535.0);
            ASSERT_EQ(table.depth[std::size_t(grid.bin_index(i, j)) * table.texel_count() +
                                  std::size_t(y) * n + x],
                      uint16_t(code))
                << "texel (" << x << ", " << y << "), bin (" << i << ", " << j << ")";
            ++checked;
            multi_segment += hit.t * std::hypot(o.x, o.y) > 1.0 ? 1 : 0;
          }
      }
    EXPECT_EQ(checked, table.depth.size());
    if (c.rings == 0) {
      EXPECT_GT(multi_segment, 0u);  // the tall field did need several segments
    }
  }
}

TEST(Parallax, SatHoldsExactRectangleSums) {
  FabricMaps maps = rctest::plain_weave_maps(32);
  ParallaxSettings settings;
  settings.dirs = 4;
  ParallaxTable t = bake_parallax(maps, settings);
  std::vector<uint32_t> sat = parallax_sat(t);
  ASSERT_EQ(sat.size(), t.depth.size());
  const int n = 32;
  auto s = [&](int dir, int x, int y) -> uint32_t {  // exclusive prefix over [0, x) x [0, y)
    if (x == 0 || y == 0) return 0;
    return sat[std::size_t(dir) * n * n + std::size_t(y - 1) * n + (x - 1)];
  };
  std::mt19937_64 rng(3);
  for (int k = 0; k < 2000; ++k) {
    int dir = int(rng() % 16);
    int x0 = int(rng() % n), x1 = int(rng() % n), y0 = int(rng() % n), y1 = int(rng() % n);
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    x1 += 1, y1 += 1;
    uint64_t brute = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        brute += t.depth[std::size_t(dir) * n * n + y * n + x];
    uint32_t from_sat = s(dir, x1, y1) - s(dir, x0, y1) - s(dir, x1, y0) + s(dir, x0, y0);
    ASSERT_EQ(uint64_t(from_sat), brute);
  }
  // The far corner, one texel.
  for (int dir = 0; dir < 16; ++dir)
    EXPECT_EQ(s(dir, n, n) - s(dir, n - 1, n) - s(dir, n, n - 1) + s(dir, n - 1, n - 1),
              t.depth[std::size_t(dir) * n * n + (n - 1) * n + (n - 1)]);
}

TEST(Parallax, SatWrapsModulo2To32) {
  // All codes at the maximum on a 512 x 512 tile: the total 65535 * 512^2 exceeds 2^32, and
  // rectangle sums of up to 65537 texels are still exact with unsigned wrap-around.
  ParallaxTable t;
  t.resolution = 512;
  t.dirs = 1;
  t.depth.assign(512u * 512u, 65535);
  std::vector<uint32_t> sat = parallax_sat(t);
  auto s = [&](int x, int y) -> uint32_t {
    return x == 0 || y == 0 ? 0u : sat[std::size_t(y - 1) * 512 + (x - 1)];
  };
  // A 256 x 256 block at the far corner: 65535 * 65536 = 4294901760 < 2^32.
  uint32_t sum = s(512, 512) - s(256, 512) - s(512, 256) + s(256, 256);
  EXPECT_EQ(sum, 65535u * 65536u);
}

TEST(Parallax, RejectsBadSettingsNamingTheKey) {
  FabricMaps maps = rctest::plain_weave_maps(8);
  auto expect_error = [&](ParallaxSettings s, const std::string& key) {
    try {
      bake_parallax(maps, s);
      FAIL() << "expected an error for " << key;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Input);
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  ParallaxSettings s;
  s.dirs = 0;
  expect_error(s, "bake.parallax_dirs");
  s.dirs = 257;
  expect_error(s, "bake.parallax_dirs");
  s = {};
  s.min_cos = 1.0;
  expect_error(s, "bake.parallax_min_cos");
  s.min_cos = -0.1;
  expect_error(s, "bake.parallax_min_cos");
  s.min_cos = std::nan("");
  expect_error(s, "bake.parallax_min_cos");
  maps.height[maps.index(5, 6)] = std::numeric_limits<float>::infinity();
  expect_error({}, "texel (5, 6)");
}

TEST(Parallax, RefusesTablesBeyondTheMemoryLimit) {
  // 4096^2 texels x 32^2 directions would need 96 GiB: refused before any allocation, naming the
  // keys (the height map itself is only 64 MiB).
  FabricMaps maps;
  maps.resolution = 4096;
  maps.height.assign(4096u * 4096u, 0.f);
  try {
    bake_parallax(maps, {});
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("bake.resolution = 4096"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bake.parallax_dirs = 32"), std::string::npos);
  }
}

// Visibility sampling and the per-texel ASG fit (raycast/visibility.hpp): the whole sky on a
// flat map, the horizon of a step in closed form, the exact 1-D reference on a sine, vertical
// walls, warnings, thread-count determinism; and the CGAL cross-check of Embree's hits.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "model/directions.hpp"
#include "raycast/asg_fit.hpp"
#include "raycast/visibility.hpp"
#include "tests/raycast/cgal_check.hpp"
#include "tests/raycast/reference.hpp"
#include "tests/raycast/synthetic_fields.hpp"

using namespace clothbake;
using namespace clothbake::raycast;
using model::Vec3d;

namespace {

rctest::Profile profile_of(const FabricMaps& maps) {
  rctest::Profile p;
  for (int x = 0; x < maps.resolution; ++x)
    p.h.push_back(double(maps.height[std::size_t(x)]));
  return p;
}

// The origin the stage uses for texel x of a 1-D profile (normal from central differences).
Vec3d origin_1d(const rctest::Profile& p, int x, double offset_texels) {
  const int n = int(p.h.size());
  double dhdx = (p.h[std::size_t((x + 1) % n)] - p.h[std::size_t((x + n - 1) % n)]) * n / 2;
  Vec3d normal = model::normalize(Vec3d{-dhdx, 0, 1});
  return Vec3d{(x + 0.5) / n, 0.5 / n, p.h[std::size_t(x)]} + normal * (offset_texels / n);
}

}  // namespace

TEST(Visibility, FlatMapSeesTheWholeSkyAndFitsExactly) {
  FabricMaps maps = rctest::maps_from(8, [](double, double) { return 0.1; });
  VisibilitySettings settings;
  VisibilitySamples v = sample_visibility(maps, settings);
  EXPECT_EQ(v.rays, 0u);
  for (std::size_t t = 0; t < 64; ++t)
    EXPECT_EQ(v.visible_fraction(t), 1.0);
  VisibilityAsgs a = fit_visibility(v, settings);
  for (std::size_t t = 0; t < 64; ++t) {
    auto p = model::unpack_asg<double>(a.records[t]);
    EXPECT_EQ(p.amplitude, 1.0);
    EXPECT_EQ(p.lambda, 0.0);
    EXPECT_EQ(p.mu, 0.0);
    EXPECT_EQ(a.fit_error[t], 0.0f);
  }
}

TEST(Visibility, StepHorizonMatchesItsClosedForm) {
  // Plateau H on texels x < 16 of 32, floor 0 elsewhere. From a floor texel away from the ramps
  // (origin at height z0 = offset), a direction w is blocked iff its rise over the distance to the
  // nearest plateau corner on its side is below H - z0: the corners are the plateau's end vertices
  // 15.5/32 (towards -x) and 32.5/32 (towards +x).
  const int n = 32;
  const double H = 0.15;
  FabricMaps maps = rctest::maps_from(n, [&](double u, double) { return u < 0.5 ? H : 0.0; });
  VisibilitySettings settings;
  VisibilitySamples v = sample_visibility(maps, settings);
  model::DirectionGrid<double> grid{32, 0.0};
  const double hf = double(float(H));
  int checked = 0, blocked = 0;
  for (int x = 18; x <= 29; ++x) {
    const double u = (x + 0.5) / n, z0 = settings.normal_offset_texels / n;
    for (int dir = 0; dir < 32 * 32; ++dir) {
      Vec3d w = grid.bin_center(dir % 32, dir / 32);
      bool expected = true;
      if (w.x != 0) {
        double dist = w.x > 0 ? 32.5 / n - u : u - 15.5 / n;
        double rise = dist * w.z / std::abs(w.x);
        if (std::abs(rise - (hf - z0)) < 1e-5) continue;  // grazing the corner: either is right
        expected = rise > hf - z0;
      }
      ASSERT_EQ(v.visible(std::size_t(7 * n + x), dir), expected) << "x " << x << " dir " << dir;
      ++checked;
      blocked += !expected;
    }
  }
  EXPECT_GT(checked, 12000);
  EXPECT_GT(blocked, 1000);
}

TEST(Visibility, SineFieldMatchesTheExactReference) {
  const int n = 64;
  FabricMaps maps =
      rctest::maps_from(n, [](double u, double) { return 0.04 * std::sin(2 * M_PI * 2 * u); });
  VisibilitySettings settings;
  settings.dirs = 16;
  VisibilitySamples v = sample_visibility(maps, settings);
  rctest::Profile p = profile_of(maps);
  model::DirectionGrid<double> grid{16, 0.0};
  const double z_max = *std::max_element(p.h.begin(), p.h.end());
  int mismatches = 0;
  for (int x = 0; x < n; ++x) {
    Vec3d o = origin_1d(p, x, settings.normal_offset_texels);
    for (int dir = 0; dir < 256; ++dir) {
      Vec3d w = grid.bin_center(dir % 16, dir / 16);
      double t_max = (z_max - o.z) / w.z + 1e-6;
      bool expected = !(rctest::first_hit_1d(p, o, w, t_max) < rctest::kNoHit);
      if (v.visible(std::size_t(3 * n + x), dir) != expected) {
        // Only tangent rays may differ: the reference must flip under a 1e-5 change of height.
        bool up = !(rctest::first_hit_1d(p, o + Vec3d{0, 0, 1e-5}, w, t_max) < rctest::kNoHit);
        bool down = !(rctest::first_hit_1d(p, o - Vec3d{0, 0, 1e-5}, w, t_max) < rctest::kNoHit);
        ASSERT_NE(up, down) << "x " << x << " dir " << dir;
        ++mismatches;
      }
    }
  }
  EXPECT_LE(mismatches, 4);
}

TEST(Visibility, DirectionsSteeperThanEverySlopeAreVisible) {
  // On a piecewise-linear height field whose triangles have gradients of norm <= s, a ray that
  // rises faster than s (w.z / |w.xy| > s) from above the surface can never meet it: every such bin
  // is visible from every texel. Rough noise, so that many other bins are blocked.
  const int n = 24;
  FabricMaps maps;
  maps.resolution = n;
  uint64_t state = 12345;
  for (int i = 0; i < n * n; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    maps.height.push_back(float((state >> 40) % 1000) / 1000.0f * 0.05f);
  }
  double s = 0;  // largest gradient norm over the two triangles of every quad
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      auto h = [&](int i, int j) {
        return double(maps.height[maps.index((i + n) % n, (j + n) % n)]);
      };
      double a = h(x, y), b = h(x + 1, y), c = h(x + 1, y + 1), d = h(x, y + 1);
      s = std::max(s, std::hypot((b - a) * n, (c - b) * n));  // triangle a-b-c
      s = std::max(s, std::hypot((c - d) * n, (d - a) * n));  // triangle a-c-d
    }
  VisibilitySettings settings;
  settings.dirs = 16;
  VisibilitySamples v = sample_visibility(maps, settings);
  model::DirectionGrid<double> grid{16, 0.0};
  int steep = 0, blocked = 0;
  for (int dir = 0; dir < 256; ++dir) {
    Vec3d w = grid.bin_center(dir % 16, dir / 16);
    bool must_see = w.z > s * std::hypot(w.x, w.y);
    steep += must_see;
    for (std::size_t t = 0; t < maps.texel_count(); ++t) {
      if (must_see) {
        ASSERT_TRUE(v.visible(t, dir)) << "texel " << t << " dir " << dir;
      }
      blocked += !v.visible(t, dir);
    }
  }
  EXPECT_GT(steep, 10);
  EXPECT_GT(blocked, 1000);
}

TEST(Visibility, VerticalWallsGiveFiniteLobes) {
  // A wall 2 tile sides high over one texel (slope 64): texels at its foot, on it and on top.
  const int n = 32;
  FabricMaps maps = rctest::maps_from(n, [](double u, double) { return u < 0.5 ? 2.0 : 0.0; });
  VisibilitySettings settings;
  settings.dirs = 16;
  VisibilitySamples v = sample_visibility(maps, settings);
  VisibilityAsgs a = fit_visibility(v, settings);
  for (int x : {14, 15, 16, 17, 31, 0}) {
    std::size_t t = std::size_t(5 * n + x);
    auto p = model::unpack_asg<double>(a.records[t]);
    EXPECT_TRUE(std::isfinite(p.lambda) && std::isfinite(p.mu) && std::isfinite(p.amplitude));
    EXPECT_TRUE(std::isfinite(a.fit_error[t]));
    EXPECT_GT(v.visible_fraction(t), 0.0);
  }
  // At the foot of the wall (x = 16) the wall hides close to half the sky; on top (x = 7), none.
  EXPECT_LT(v.visible_fraction(std::size_t(5 * n + 16)), 0.6);
  EXPECT_EQ(v.visible_fraction(std::size_t(5 * n + 7)), 1.0);
}

// Poor fits are counted and the worst texel found (the asset's metadata reports them), without a
// warning: no setting fixes a single lobe's error against a binary horizon (docs/raycast.md).
TEST(Visibility, CountsPoorFitsAndFindsTheWorstTexelWithoutAWarning) {
  FabricMaps maps = rctest::plain_weave_maps(16);
  VisibilitySettings settings;
  settings.dirs = 16;
  VisibilitySamples v = sample_visibility(maps, settings);
  take_warnings();
  settings.fit_warn_rms = 0.99;  // nothing is that bad
  VisibilityAsgs quiet = fit_visibility(v, settings);
  EXPECT_TRUE(take_warnings().empty());
  EXPECT_EQ(quiet.texels_above_warning, 0u);
  settings.fit_warn_rms = 0.02;  // almost everything is
  VisibilityAsgs loud = fit_visibility(v, settings);
  EXPECT_TRUE(take_warnings().empty());
  const std::size_t worst = loud.worst_texel;
  EXPECT_GT(loud.texels_above_warning, 0u);
  EXPECT_EQ(loud.max_fit_error, double(loud.fit_error[worst]));
  for (float e : loud.fit_error)
    EXPECT_LE(double(e), loud.max_fit_error);
}

TEST(Visibility, SameBitsAndLobesForAnyThreadCount) {
  FabricMaps maps = rctest::plain_weave_maps(40);
  VisibilitySettings settings;
  settings.dirs = 12;
  VisibilitySamples v1, v2;
  VisibilityAsgs a1, a2;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    v1 = sample_visibility(maps, settings);
    a1 = fit_visibility(v1, settings);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    v2 = sample_visibility(maps, settings);
    a2 = fit_visibility(v2, settings);
  }
  EXPECT_EQ(v1.bits, v2.bits);
  ASSERT_EQ(a1.records.size(), a2.records.size());
  EXPECT_EQ(std::memcmp(a1.records.data(), a2.records.data(),
                        a1.records.size() * sizeof(model::AsgRecord)),
            0);
  EXPECT_EQ(a1.fit_error, a2.fit_error);
  EXPECT_EQ(a1.mean_fit_error, a2.mean_fit_error);
}

// Texels with the same samples share one fit: the records and errors are those of fitting every
// texel on its own (fit_asg, pack_asg, asg_rms_error of the packed lobe), and a woven tile, whose
// relief repeats, has fewer distinct patterns than texels. The worst texel is the first in texel
// order with the largest error.
TEST(Visibility, DistinctPatternsAreFittedOnceWithEveryTexelsOwnResult) {
  FabricMaps maps = rctest::plain_weave_maps(32);
  VisibilitySettings settings;
  settings.dirs = 10;
  VisibilitySamples v = sample_visibility(maps, settings);
  VisibilityAsgs a = fit_visibility(v, settings);
  const std::size_t texels = maps.texel_count();
  EXPECT_GT(a.distinct_patterns, 1u);
  EXPECT_LT(a.distinct_patterns, texels);
  const FitDirections directions = visibility_fit_directions(settings.dirs);
  std::vector<uint8_t> visible(std::size_t(settings.dirs * settings.dirs));
  double largest = -1;
  std::size_t first_largest = 0;
  for (std::size_t t = 0; t < texels; ++t) {
    for (std::size_t k = 0; k < visible.size(); ++k)
      visible[k] = v.visible(t, int(k)) ? 1 : 0;
    const model::AsgRecord record = model::pack_asg(fit_asg(directions, visible.data()).params);
    ASSERT_EQ(std::memcmp(&record, &a.records[t], sizeof record), 0) << "texel " << t;
    const float error =
        float(asg_rms_error(directions, visible.data(), model::unpack_asg<double>(record)));
    ASSERT_EQ(error, a.fit_error[t]) << "texel " << t;
    if (double(error) > largest) largest = double(error), first_largest = t;
  }
  EXPECT_EQ(a.worst_texel, first_largest);
  EXPECT_EQ(a.max_fit_error, largest);
}

TEST(Visibility, RejectsBadSettings) {
  FabricMaps maps = rctest::plain_weave_maps(8);
  VisibilitySettings s;
  s.dirs = 0;
  EXPECT_THROW(sample_visibility(maps, s), Error);
  s = {};
  s.normal_offset_texels = 0;
  EXPECT_THROW(sample_visibility(maps, s), Error);
  try {
    s = {};
    s.dirs = 300;
    sample_visibility(maps, s);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bake.visibility_dirs"), std::string::npos);
  }
}

TEST(Visibility, RefusesSampleSetsBeyondTheMemoryLimit) {
  FabricMaps maps;
  maps.resolution = 8192;
  maps.height.assign(8192u * 8192u, 0.f);
  VisibilitySettings s;
  s.dirs = 64;  // 8192^2 x 64^2 bits = 32 GiB
  try {
    sample_visibility(maps, s);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("bake.visibility_dirs = 64"), std::string::npos)
        << e.what();
  }
}

// ---- CGAL cross-check -------------------------------------------------------------------------

TEST(CgalCrossCheck, EmbreeAgreesWithExactPredicatesOnAWeave) {
  FabricMaps maps = rctest::plain_weave_maps(32);
  CrossCheckSettings s;
  s.texels = 48;
  s.dirs = 8;
  CrossCheckReport r = cross_check_with_cgal(maps, s);
  EXPECT_EQ(r.disagreements, 0) << (r.examples.empty() ? "" : r.examples[0]);
  EXPECT_GT(r.rays, 5000);
  EXPECT_LE(r.near_edge_disagreements, r.rays / 200);
  EXPECT_LT(r.max_difference, 1e-4);
  std::printf("weave: %d rays, %d agree, %d near-edge, %d skipped, max |dt| %.2e\n", r.rays,
              r.agreements, r.near_edge_disagreements, r.skipped, r.max_difference);
}

TEST(CgalCrossCheck, EmbreeAgreesOnRoughAndTallFields) {
  // Random heights (many slivers and steep triangles) and a field 1.5 tiles tall (segments).
  for (double scale : {0.2, 1.5}) {
    const int n = 16;
    FabricMaps maps;
    maps.resolution = n;
    uint64_t state = 99;
    for (int i = 0; i < n * n; ++i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      maps.height.push_back(float(double((state >> 33) % 10000) / 10000.0 * scale));
    }
    CrossCheckSettings s;
    s.texels = 40;
    s.dirs = 8;
    s.rings = 0;  // the smallest neighbourhood: most rays are cut into segments
    CrossCheckReport r = cross_check_with_cgal(maps, s);
    EXPECT_EQ(r.disagreements, 0) << (r.examples.empty() ? "" : r.examples[0]);
    EXPECT_GT(r.rays, 1000);
    EXPECT_LE(r.near_edge_disagreements, r.rays / 100);
    std::printf("scale %.1f: %d rays, %d agree, %d near-edge, %d skipped, max |dt| %.2e\n", scale,
                r.rays, r.agreements, r.near_edge_disagreements, r.skipped, r.max_difference);
  }
}

// The sideways budget in the visibility stage: with a budget shorter than the relief needs, rays
// that would be blocked beyond it count as visible, the count is reported and warned about, and
// nothing else changes (every bit that differs from the unlimited samples is such a ray).
TEST(Visibility, RaysCutByTheSidewaysBudgetCountAsVisibleAndAreReported) {
  FabricMaps maps = rctest::plain_weave_maps(16, 4, 0.5, 0.2);  // a tall weave: long shadows
  VisibilitySettings settings;
  settings.dirs = 12;
  take_warnings();
  const VisibilitySamples full = sample_visibility(maps, settings);
  EXPECT_EQ(full.unresolved_rays, 0u);
  EXPECT_EQ(full.max_sideways_tiles, kMaxSidewaysTiles);
  EXPECT_TRUE(take_warnings().empty());
  settings.max_sideways_tiles = 0.05;
  const VisibilitySamples cut = sample_visibility(maps, settings);
  const auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find(std::to_string(cut.unresolved_rays) + " of "), std::string::npos)
      << warnings[0];
  EXPECT_GT(cut.unresolved_rays, 0u);
  uint64_t gained = 0;
  for (std::size_t t = 0; t < maps.texel_count(); ++t)
    for (int dir = 0; dir < 144; ++dir) {
      EXPECT_TRUE(cut.visible(t, dir) || !full.visible(t, dir)) << "lost a visible ray";
      gained += cut.visible(t, dir) && !full.visible(t, dir);
    }
  EXPECT_GT(gained, 0u);
  EXPECT_LE(gained, cut.unresolved_rays);
  settings.max_sideways_tiles = 0;
  EXPECT_THROW(sample_visibility(maps, settings), Error);
}

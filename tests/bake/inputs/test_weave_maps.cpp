// Procedural weave maps: tileability, unit tangents, normals against the height gradient, gaps,
// closed forms at crossings, twist, colours, determinism and input validation.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "bake/inputs/weave_maps.hpp"
#include "common/error.hpp"

using namespace clothbake;
using namespace clothbake::weave;

namespace {

constexpr double kPi = 3.14159265358979323846;

WeaveSpec make_spec(const WeaveMatrix& m, double warp_width = 0.9, double weft_width = 0.9) {
  WeaveSpec spec;
  spec.matrix = m;
  spec.warp = {0.5, warp_width, 0.15, 20.0};
  spec.weft = {0.5, weft_width, 0.15, 20.0};
  return spec;
}

// A spec with coloured threads, unequal systems and per-thread overrides.
WeaveSpec rich_spec() {
  WeaveSpec spec = make_spec(twill(2, 1, false), 0.8, 0.85);
  spec.weft.spacing_mm = 0.8;
  spec.weft.height_mm = 0.25;
  spec.weft.twist_deg = -15;
  spec.end_colors = {{0.9, 0.1, 0.1}, {0.1, 0.9, 0.1}, {0.1, 0.1, 0.9}};
  spec.pick_colors = {{0.5, 0.5, 0.5}, {0.2, 0.3, 0.4}, {0.7, 0.6, 0.5}};
  spec.end_geometry = {spec.warp, spec.warp, spec.warp};
  spec.end_geometry[1].spacing_mm = 0.7;
  spec.end_geometry[1].height_mm = 0.2;
  spec.end_geometry[2].width = 0.6;
  return spec;
}

double length(const Vec3f& v) {
  return std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
}
double dot(const Vec3f& a, const Vec3f& b) {
  return double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
}
double angle_deg(const model::Vec3d& a, const model::Vec3d& b) {
  const double c = model::dot(model::normalize(a), model::normalize(b));
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi;
}

template <class Fn>
void expect_input_error(Fn&& fn, const std::string& fragment) {
  try {
    fn();
    ADD_FAILURE() << "no error thrown, expected one mentioning " << fragment;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
        << "'" << e.what() << "' lacks '" << fragment << "'";
  }
}

// Maps of `spec` with texel (x, y) taken from (x + dx, y + dy) of `maps` (periodically).
float rolled_height(const FabricMaps& maps, int x, int y) {
  const int n = maps.resolution;
  return maps.height[maps.index(((x % n) + n) % n, ((y % n) + n) % n)];
}

}  // namespace

// The tile is the sum of the spacings rounded once: eight ends of 0.4 mm and eight picks of 0.1 mm
// are 3.2 and 0.8 mm exactly as doubles (a running double sum gave 3.1999999999999997, which a
// written fabric.toml showed), and per-thread spacings are summed the same way.
TEST(WeaveMaps, TileSizeIsTheCorrectlyRoundedSumOfTheSpacings) {
  WeaveSpec eight = make_spec(twill(4, 4, false));
  eight.warp.spacing_mm = 0.4;
  eight.weft.spacing_mm = 0.1;
  ASSERT_EQ(eight.matrix.ends, 8);
  const TileSize t = weave_tile_size(eight);
  EXPECT_EQ(t.width_mm, 3.2);
  EXPECT_EQ(t.height_mm, 0.8);
  double running = 0;
  for (int e = 0; e < 8; ++e)
    running += 0.4;
  EXPECT_NE(running, 3.2);  // what the test guards against
  eight.end_geometry.assign(8, eight.warp);
  EXPECT_EQ(weave_tile_size(eight).width_mm, 3.2);
}

// A tile of several repeats: the matrix tiled, per-thread lists repeated, the tile's sides the
// repeat's times the counts; the maps of [1, 1] are the spec's own.
TEST(WeaveMaps, RepeatedSpecTilesTheMatrixAndItsThreads) {
  WeaveSpec spec = rich_spec();
  const WeaveSpec r = repeat_weave_spec(spec, 2, 3);
  ASSERT_EQ(r.matrix.ends, 2 * spec.matrix.ends);
  ASSERT_EQ(r.matrix.picks, 3 * spec.matrix.picks);
  for (int p = 0; p < r.matrix.picks; ++p)
    for (int e = 0; e < r.matrix.ends; ++e)
      EXPECT_EQ(r.matrix.warp_up(p, e),
                spec.matrix.warp_up(p % spec.matrix.picks, e % spec.matrix.ends));
  ASSERT_EQ(r.end_colors.size(), 2 * spec.end_colors.size());
  EXPECT_EQ(r.end_colors[spec.end_colors.size() + 1], spec.end_colors[1]);
  ASSERT_EQ(r.pick_colors.size(), 3 * spec.pick_colors.size());
  ASSERT_EQ(r.end_geometry.size(), 2 * spec.end_geometry.size());
  EXPECT_EQ(r.end_geometry[spec.end_geometry.size() + 1].spacing_mm,
            spec.end_geometry[1].spacing_mm);
  const TileSize one = weave_tile_size(spec), tiled = weave_tile_size(r);
  EXPECT_NEAR(tiled.width_mm, 2 * one.width_mm, 1e-12);
  EXPECT_NEAR(tiled.height_mm, 3 * one.height_mm, 1e-12);
  const WeaveSpec same = repeat_weave_spec(spec, 1, 1);
  EXPECT_EQ(same.matrix, spec.matrix);
  EXPECT_EQ(same.end_colors, spec.end_colors);
  // A tile beyond the largest repeat (kMaxRepeat ends) is refused, naming where it was asked.
  WeaveSpec wide = spec;
  wide.matrix = make_matrix(2, 300);
  wide.end_colors.clear();
  wide.end_geometry.clear();
  wide.pick_colors.clear();
  wide.pick_geometry.clear();
  try {
    (void)repeat_weave_spec(wide, 16, 1, "f.toml:3:10: weave.repeat");
    FAIL() << "no error for 4800 ends";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input);
    EXPECT_NE(std::string(e.what()).find("f.toml:3:10: weave.repeat"), std::string::npos)
        << e.what();
  }
}

TEST(WeaveMaps, EveryMapIsWellFormed) {
  for (const WeaveSpec& spec : {make_spec(plain_weave()), make_spec(satin(5, 2), 0.7, 1.0),
                                make_spec(basket(2), 1.0, 0.6), rich_spec()}) {
    const int n = 97;  // not a multiple of anything: texel centres fall anywhere
    const FabricMaps maps = generate_weave_maps(spec, n);
    ASSERT_EQ(maps.resolution, n);
    for (auto size : {maps.height.size(), maps.tangent.size(), maps.normal.size(), maps.gap.size(),
                      maps.yarn_id.size(), maps.albedo.size()})
      ASSERT_EQ(size, maps.texel_count());
    for (std::size_t i = 0; i < maps.texel_count(); ++i) {
      ASSERT_TRUE(std::isfinite(maps.height[i]));
      EXPECT_NEAR(length(maps.tangent[i]), 1.0, 1e-6) << i;
      EXPECT_NEAR(length(maps.normal[i]), 1.0, 1e-6) << i;
      EXPECT_GT(maps.normal[i][2], 0.05f) << i;  // the rim's tangent line bounds the slope
      EXPECT_LT(std::fabs(dot(maps.tangent[i], maps.normal[i])), 1e-5) << i;
      EXPECT_TRUE(maps.gap[i] == 0.0f || maps.gap[i] == 1.0f);
      EXPECT_LE(maps.yarn_id[i], 1);
      for (float c : maps.albedo[i])
        EXPECT_TRUE(c >= 0.0f && c <= 1.0f);
    }
  }
}

// The strongest tileability check: shifting the weave matrix by k ends (picks) must shift every
// map by exactly k * N / ends columns (rows), wherever the seam lands.
TEST(WeaveMaps, ShiftingTheRepeatShiftsTheMapsAcrossTheSeam) {
  for (const WeaveMatrix& m : {twill(2, 1, false), satin(5, 3), basket(2), twill(3, 1, true)}) {
    WeaveSpec spec = make_spec(m, 0.83, 0.77);
    const int n = 60 * m.ends;  // ends == picks for these weaves
    const int per_thread = n / m.ends;
    const FabricMaps base = generate_weave_maps(spec, n);
    for (int k = 1; k < m.ends; ++k) {
      for (bool along_picks : {false, true}) {
        WeaveSpec shifted = spec;
        shifted.matrix = along_picks ? m.rolled(k, 0) : m.rolled(0, k);
        const FabricMaps maps = generate_weave_maps(shifted, n);
        int mismatches = 0;
        for (int y = 0; y < n; ++y) {
          for (int x = 0; x < n; ++x) {
            const int sx = along_picks ? x : x - k * per_thread;
            const int sy = along_picks ? y - k * per_thread : y;
            const std::size_t i = maps.index(x, y);
            const std::size_t j = base.index(((sx % n) + n) % n, ((sy % n) + n) % n);
            if (maps.yarn_id[i] != base.yarn_id[j] || maps.gap[i] != base.gap[j]) {
              ++mismatches;
              continue;
            }
            EXPECT_NEAR(maps.height[i], base.height[j], 1e-6);
            for (int c = 0; c < 3; ++c) {
              EXPECT_NEAR(maps.normal[i][c], base.normal[j][c], 1e-5);
              EXPECT_NEAR(maps.tangent[i][c], base.tangent[j][c], 1e-5);
            }
          }
        }
        EXPECT_EQ(mismatches, 0) << "k=" << k << (along_picks ? " picks" : " ends");
      }
    }
  }
}

// The texel after the last one is the first: the analytic surface is periodic, and the differences
// across the seam look like the differences inside the tile.
TEST(WeaveMaps, SeamDifferencesMatchInteriorDifferences) {
  for (const WeaveSpec& spec : {make_spec(twill(2, 2, false)), rich_spec()}) {
    const int n = 128;
    const FabricMaps maps = generate_weave_maps(spec, n);
    const WeaveSurface surface(spec);
    // Periodicity of the sampled function at the texel centres of the neighbouring tiles.
    for (int t = 0; t < n; t += 7) {
      const double c = (t + 0.5) / n;
      const WeaveSample last = surface.sample((n - 0.5) / n, c);
      const WeaveSample before_first = surface.sample(-0.5 / n, c);
      EXPECT_NEAR(before_first.height, last.height, 1e-12);
      EXPECT_EQ(before_first.yarn_id, last.yarn_id);
      const WeaveSample first = surface.sample(0.5 / n, c);
      const WeaveSample after_last = surface.sample(1.0 + 0.5 / n, c);
      EXPECT_NEAR(after_last.height, first.height, 1e-12);
      EXPECT_NEAR(after_last.normal.x, first.normal.x, 1e-9);
      EXPECT_EQ(surface.sample(c, 1.0 + 0.5 / n).thread, surface.sample(c, 0.5 / n).thread);
    }
    // Height differences across the seam (x = N-1 -> 0, y = N-1 -> 0) against the interior.
    double interior_max = 0, interior_sum = 0, seam_max = 0, seam_sum = 0;
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b + 1 < n; ++b) {
        const double dx = std::fabs(rolled_height(maps, b + 1, a) - rolled_height(maps, b, a));
        const double dy = std::fabs(rolled_height(maps, a, b + 1) - rolled_height(maps, a, b));
        interior_max = std::max({interior_max, dx, dy});
        interior_sum += dx + dy;
      }
      const double sx = std::fabs(rolled_height(maps, 0, a) - rolled_height(maps, n - 1, a));
      const double sy = std::fabs(rolled_height(maps, a, 0) - rolled_height(maps, a, n - 1));
      seam_max = std::max({seam_max, sx, sy});
      seam_sum += sx + sy;
    }
    const double interior_mean = interior_sum / (2.0 * n * (n - 1));
    const double seam_mean = seam_sum / (2.0 * n);
    EXPECT_LE(seam_max, interior_max);
    EXPECT_LE(seam_mean, 3.0 * interior_mean);
  }
}

TEST(WeaveMaps, NormalIsTheNormalisedHeightGradient) {
  for (const WeaveSpec& spec :
       {make_spec(plain_weave()), make_spec(satin(5, 2), 0.8, 0.9), rich_spec()}) {
    const WeaveSurface surface(spec);
    // 1. Analytic gradient against fine central differences of the analytic height, at random
    //    points away from silhouettes (the same yarn at all four stencil points).
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const double h = 1e-7;
    int checked = 0;
    for (int trial = 0; trial < 4000; ++trial) {
      const double u = uniform(rng), v = uniform(rng);
      const WeaveSample s = surface.sample(u, v);
      if (s.gap == 0) continue;
      const WeaveSample xp = surface.sample(u + h, v), xm = surface.sample(u - h, v);
      const WeaveSample yp = surface.sample(u, v + h), ym = surface.sample(u, v - h);
      bool smooth = true;
      for (const WeaveSample* o : {&xp, &xm, &yp, &ym})
        smooth &= o->gap == 1 && o->yarn_id == s.yarn_id && o->thread == s.thread;
      if (!smooth) continue;
      const double du = (xp.height - xm.height) / (2 * h), dv = (yp.height - ym.height) / (2 * h);
      const double scale = 1.0 + std::fabs(s.dh_du) + std::fabs(s.dh_dv);
      EXPECT_NEAR(du, s.dh_du, 2e-4 * scale) << u << "," << v;
      EXPECT_NEAR(dv, s.dh_dv, 2e-4 * scale) << u << "," << v;
      const model::Vec3d expected = model::normalize(model::Vec3d{-s.dh_du, -s.dh_dv, 1.0});
      EXPECT_LT(model::length(expected - s.normal), 1e-12);
      ++checked;
    }
    EXPECT_GT(checked, 2000);

    // 2. The stored normal map against central differences of the stored height map, in the
    //    smooth interior of yarns: every stencil texel on the same yarn surface, away from the
    //    elliptical rim (|normal.z| large). The discretisation error is O(1/N^2).
    const int n = 512;
    const FabricMaps maps = generate_weave_maps(spec, n);
    auto at = [&](int x, int y) { return maps.index(((x % n) + n) % n, ((y % n) + n) % n); };
    // The thread owning a texel: the end of its column (warp) or the pick of its row (weft).
    std::vector<int> column_end(static_cast<std::size_t>(n)), row_pick(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      column_end[std::size_t(i)] =
          surface.locate_end((i + 0.5) / n * surface.tile().width_mm).owner;
      row_pick[std::size_t(i)] =
          surface.locate_pick((i + 0.5) / n * surface.tile().height_mm).owner;
    }
    auto thread = [&](int x, int y) {
      const std::size_t i = at(x, y);
      return maps.yarn_id[i] == 0 ? column_end[std::size_t(((x % n) + n) % n)]
                                  : row_pick[std::size_t(((y % n) + n) % n)];
    };
    double worst = 0;
    int compared = 0;
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const std::size_t c = at(x, y);
        if (maps.gap[c] == 0 || maps.normal[c][2] < 0.6f) continue;
        bool smooth = true;
        for (auto [ox, oy] :
             {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {2, 0}, {-2, 0}, {0, 2}, {0, -2}}) {
          const std::size_t o = at(x + ox, y + oy);
          smooth &= maps.gap[o] == 1 && maps.yarn_id[o] == maps.yarn_id[c] &&
                    thread(x + ox, y + oy) == thread(x, y) && maps.normal[o][2] > 0.6f;
        }
        if (!smooth) continue;
        const double du = (maps.height[at(x + 1, y)] - maps.height[at(x - 1, y)]) * n / 2.0;
        const double dv = (maps.height[at(x, y + 1)] - maps.height[at(x, y - 1)]) * n / 2.0;
        const model::Vec3d fd{-du, -dv, 1.0};
        const model::Vec3d stored{maps.normal[c][0], maps.normal[c][1], maps.normal[c][2]};
        worst = std::max(worst, angle_deg(fd, stored));
        ++compared;
      }
    }
    EXPECT_GT(compared, n * n / 4);
    EXPECT_LT(worst, 1.0) << "worst angle between stored and finite-difference normals";
    std::printf("normal vs central-difference normal at N=%d: worst %.4f deg over %d texels\n", n,
                worst, compared);
  }
}

TEST(WeaveMaps, GapsCoverExactlyTheUncoveredArea) {
  // Uniform spacing: a texel is a gap iff it is outside both yarn bands, so the gap fraction is
  // (1 - warp.width) (1 - weft.width) up to one texel per band edge.
  struct Case {
    WeaveMatrix m;
    double ww, wf;
  };
  for (const Case& c :
       {Case{plain_weave(), 0.7, 0.8}, Case{twill(2, 1, false), 0.5, 0.9},
        Case{satin(5, 2), 0.95, 0.6}, Case{basket(2), 1.0, 0.7}, Case{plain_weave(), 1.0, 1.0}}) {
    const WeaveSpec spec = make_spec(c.m, c.ww, c.wf);
    const int n = 400;
    const FabricMaps maps = generate_weave_maps(spec, n);
    const double floor_height = WeaveSurface(spec).floor_height();
    std::size_t gaps = 0;
    float lowest_yarn = 1e9f;
    for (std::size_t i = 0; i < maps.texel_count(); ++i) {
      if (maps.gap[i] == 0) {
        ++gaps;
        EXPECT_FLOAT_EQ(maps.height[i], float(floor_height));
        EXPECT_FLOAT_EQ(maps.normal[i][2], 1.0f);
      } else {
        lowest_yarn = std::min(lowest_yarn, maps.height[i]);
      }
    }
    const double expected = (1.0 - c.ww) * (1.0 - c.wf);
    const double tolerance = 2.0 * (c.m.ends + c.m.picks) / n;
    EXPECT_NEAR(double(gaps) / double(maps.texel_count()), expected, tolerance)
        << c.ww << " x " << c.wf;
    if (c.ww == 1.0 && c.wf == 1.0) {
      EXPECT_EQ(gaps, 0u);
    }
    if (c.ww < 1.0 && c.wf < 1.0) {
      EXPECT_GT(gaps, 0u);
    }
    EXPECT_GT(lowest_yarn, float(floor_height));  // gaps are the lowest points of the fabric
  }
}

TEST(WeaveMaps, CrossingsShowTheThreadOnTopAtTheClosedFormHeight) {
  const WeaveSpec spec = rich_spec();
  const WeaveSurface surface(spec);
  const TileSize tile = surface.tile();
  EXPECT_NEAR(tile.width_mm, 0.5 + 0.7 + 0.5, 1e-12);
  EXPECT_NEAR(tile.height_mm, 3 * 0.8, 1e-12);
  EXPECT_NEAR(tile.height_unit_mm, tile.width_mm, 0);
  const double end_centres[] = {0.25, 0.5 + 0.35, 1.2 + 0.25};
  const double end_half_heights[] = {0.075, 0.1, 0.075};
  for (int p = 0; p < 3; ++p) {
    for (int e = 0; e < 3; ++e) {
      const double u = end_centres[e] / tile.width_mm, v = (0.4 + 0.8 * p) / tile.height_mm;
      const WeaveSample s = surface.sample(u, v);
      const bool up = spec.matrix.warp_up(p, e);
      EXPECT_EQ(s.yarn_id, up ? 0 : 1) << p << "," << e;
      EXPECT_EQ(s.thread, up ? e : p);
      // The yarn on top sits half the crossing yarn's thickness above the mid-plane and adds its
      // own half-thickness: (b_pick + b_end) / W. The crimp is flat at a crossing.
      EXPECT_NEAR(s.height, (0.125 + end_half_heights[e]) / tile.width_mm, 1e-12);
      EXPECT_NEAR(s.dh_du, 0, 1e-12);
      EXPECT_NEAR(s.dh_dv, 0, 1e-12);
      const Rgb expected = up ? spec.end_colors[std::size_t(e)] : spec.pick_colors[std::size_t(p)];
      EXPECT_EQ(s.color, expected);
    }
  }
}

TEST(WeaveMaps, PlainWeaveCrimpIsASinusoid) {
  // Along a warp end's centre line the centre follows b_weft * cos(pi (y - y_p) / s) where it is
  // on top (|y - y_p| < s / 4 around a crossing where it is up), plus its own half-thickness.
  WeaveSpec spec = make_spec(plain_weave(), 0.9, 0.9);
  spec.weft.height_mm = 0.2;
  const WeaveSurface surface(spec);
  const double W = surface.tile().width_mm, b_weft = 0.1, b_warp = 0.075, s = 0.5;
  for (double offset = -0.12; offset <= 0.12; offset += 0.01) {
    const double y = 0.25 + offset;  // crossing of end 0 over pick 0
    const WeaveSample sample = surface.sample(0.25 / W, y / surface.tile().height_mm);
    ASSERT_EQ(sample.yarn_id, 0);
    EXPECT_NEAR(sample.height * W, b_weft * std::cos(kPi * offset / s) + b_warp, 1e-12);
  }
}

TEST(WeaveMaps, TwistRotatesTheFibreClockwiseFromTheYarnAxis) {
  for (double twist : {0.0, 20.0, -35.0}) {
    WeaveSpec spec = make_spec(plain_weave());
    spec.warp.twist_deg = twist;
    spec.weft.twist_deg = twist;
    const WeaveSurface surface(spec);
    const double psi = twist * kPi / 180.0;
    // Warp on top at (pick 0, end 0): flat, axis +v; the fibre leans toward +u for psi > 0.
    WeaveSample s = surface.sample(0.25, 0.25);
    ASSERT_EQ(s.yarn_id, 0);
    EXPECT_NEAR(s.tangent.x, std::sin(psi), 1e-12);
    EXPECT_NEAR(s.tangent.y, std::cos(psi), 1e-12);
    EXPECT_NEAR(s.tangent.z, 0, 1e-12);
    // Weft on top at (pick 0, end 1): axis +u; clockwise means toward -v.
    s = surface.sample(0.75, 0.25);
    ASSERT_EQ(s.yarn_id, 1);
    EXPECT_NEAR(s.tangent.x, std::cos(psi), 1e-12);
    EXPECT_NEAR(s.tangent.y, -std::sin(psi), 1e-12);
  }
  // Off the crossing the untwisted tangent follows the crimp: the warp axis climbs with dh/dv.
  WeaveSpec spec = make_spec(plain_weave());
  spec.warp.twist_deg = 0;
  const WeaveSurface surface(spec);
  const WeaveSample s = surface.sample(0.25, 0.3);
  ASSERT_EQ(s.yarn_id, 0);
  EXPECT_LT(s.dh_dv, 0);  // descending from the crossing towards the next pick
  EXPECT_NEAR(s.tangent.z / s.tangent.y, s.dh_dv, 1e-12);
  EXPECT_NEAR(s.tangent.x, 0, 1e-12);
}

TEST(WeaveMaps, SampleMatchesTheMapAtTexelCentres) {
  const WeaveSpec spec = rich_spec();
  const int n = 64;
  const FabricMaps maps = generate_weave_maps(spec, n);
  const WeaveSurface surface(spec);
  for (int y = 0; y < n; y += 3) {
    for (int x = 0; x < n; x += 5) {
      const WeaveSample s = surface.sample((x + 0.5) / n, (y + 0.5) / n);
      const std::size_t i = maps.index(x, y);
      EXPECT_EQ(maps.height[i], float(s.height));
      EXPECT_EQ(maps.yarn_id[i], s.yarn_id);
      EXPECT_EQ(maps.albedo[i][0], float(s.color[0]));
      EXPECT_EQ(maps.normal[i][0], float(s.normal.x));
    }
  }
}

TEST(WeaveMaps, DeterministicWhateverTheThreadCount) {
  const WeaveSpec spec = rich_spec();
  const FabricMaps a = generate_weave_maps(spec, 200);
  FabricMaps b;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    b = generate_weave_maps(spec, 200);
  }
  const FabricMaps c = generate_weave_maps(spec, 200);
  for (const FabricMaps* other : {static_cast<const FabricMaps*>(&b), &c}) {
    EXPECT_EQ(std::memcmp(a.height.data(), other->height.data(), a.height.size() * 4), 0);
    EXPECT_EQ(std::memcmp(a.normal.data(), other->normal.data(), a.normal.size() * 12), 0);
    EXPECT_EQ(std::memcmp(a.tangent.data(), other->tangent.data(), a.tangent.size() * 12), 0);
    EXPECT_EQ(a.gap, other->gap);
    EXPECT_EQ(a.yarn_id, other->yarn_id);
    EXPECT_EQ(std::memcmp(a.albedo.data(), other->albedo.data(), a.albedo.size() * 12), 0);
  }
}

TEST(WeaveMaps, BadSpecsAreRejectedNamingTheField) {
  auto with = [](auto change) {
    WeaveSpec spec = rich_spec();
    change(spec);
    return spec;
  };
  const std::vector<std::pair<WeaveSpec, std::string>> cases = {
      {with([](WeaveSpec& s) { s.warp.width = 0; }), "warp.width = 0"},
      {with([](WeaveSpec& s) { s.weft.width = 1.5; }), "weft.width = 1.5"},
      {with([](WeaveSpec& s) { s.warp.spacing_mm = -1; }), "warp.spacing_mm"},
      {with([](WeaveSpec& s) { s.weft.height_mm = std::nan(""); }), "weft.height_mm"},
      {with([](WeaveSpec& s) { s.warp.twist_deg = 90; }), "warp.twist_deg"},
      {with([](WeaveSpec& s) { s.end_colors.pop_back(); }), "end_colors has 2 entries"},
      {with([](WeaveSpec& s) { s.pick_colors[1][2] = 1.2; }), "pick_colors of pick 2"},
      {with([](WeaveSpec& s) { s.end_geometry.push_back(s.warp); }), "end_geometry has 4"},
      {with([](WeaveSpec& s) { s.end_geometry[2].spacing_mm = 0; }), "end 3 geometry.spacing"},
      {with([](WeaveSpec& s) {
         s.pick_geometry = {s.weft, s.weft, s.weft};
         s.pick_geometry[0].width = 2;
       }),
       "pick 1 geometry.width"},
      {with([](WeaveSpec& s) {
         s.matrix = matrix_from_rows({"10", "10"}, "m");
         s.end_colors.clear();
         s.end_geometry.clear();
         s.pick_colors.clear();
       }),
       "end 1"},
  };
  for (const auto& entry : cases) {
    // Not a structured binding: clang 14 cannot capture one in a lambda.
    const WeaveSpec& spec = entry.first;
    const std::string& fragment = entry.second;
    expect_input_error([&] { generate_weave_maps(spec, 8); }, fragment);
    expect_input_error([&] { validate_weave_spec(spec, "fabric.toml: [weave]"); },
                       "fabric.toml: [weave]");
  }
  expect_input_error([] { generate_weave_maps(rich_spec(), 0, "f.toml: [weave]"); },
                     "f.toml: [weave]: map resolution 0");
  expect_input_error(
      [] {
        WeaveSpec spec = rich_spec();
        spec.warp.width = -1;
        generate_weave_maps(spec, 8, "f.toml: [weave]");
      },
      "f.toml: [weave]: warp.width");
  expect_input_error([] { generate_weave_maps(rich_spec(), kMaxMapResolution + 1); }, "resolution");
}

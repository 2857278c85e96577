// The unbiased multi-scale estimate below a period (eval/footprint_cover.hpp,
// eval/subperiod_sums.hpp; docs/evaluator.md, "Footprints below a period"): the block cover adds
// up to the footprint point by point, the block prefix sums are the moved blocks, every form is
// unbiased on sub-tile footprints, the unbiasedness test catches a base 3 % off, and the block grid
// follows the memory budget.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "eval/eval_data.hpp"
#include "eval/footprint_cover.hpp"
#include "eval/methods.hpp"
#include "eval/texel_shading.hpp"
#include "eval/visibility_pilot.hpp"
#include "tests/eval/eval_fixtures.hpp"
#include "tests/eval/eval_stats.hpp"

namespace clothbake::eval {
namespace {

using namespace eval_test;

// The least variance ratios against brute force the dyed-threads test accepts (measured in its
// output: without a base 135 with each texel's albedo, 11 with the cluster's mean; with the block
// form and whole periods 110 and 96 with the texel's albedo in g_V, 12 and 12 without: scratch
// mutations).
constexpr double kDyedThreadsRatioFloor = 40.0;
constexpr double kDyedThreadsBaseRatioFloor = 35.0;

std::unique_ptr<Opened> open_with(const std::string& path, const EvalOptions& options) {
  auto o = std::make_unique<Opened>();
  Status s = o->asset.open_file(path.c_str());
  EXPECT_TRUE(s.ok()) << s.message();
  s = o->evaluator.open(o->asset, options);
  EXPECT_TRUE(s.ok()) << s.message();
  return o;
}

// g_V's attenuation the texel's own in every band (the pilot's decision, set after open).
void set_texel_attenuation(const Opened& o) {
  for (bool& pays : const_cast<EvalData*>(evaluator_data(o.evaluator))->attenuation_pays)
    pays = true;
}

EvalOptions forced(FootprintBase base, uint32_t rank = UINT32_MAX) {
  EvalOptions options;
  options.footprint_base = base;
  options.block_sum_rank = rank;
  options.max_block_sum_bytes = 1e12;      // 16 x 16 blocks of 4 texels on the 64^2 fixtures
  options.min_control_variate_side = 0.0;  // never brute force: every footprint takes the form
  return options;
}

bool inside(const Footprint& r, double x, double y) {
  return x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
}

// The block form, point by point: the base integrates g_r over A, the interior g - g_r, the strips
// 1_P g - 1_A g_r, so at every point of the plane the coefficients of g and g_r add up to 1_P and 0
// (with the full rank, g_r is g and only their sum counts). A is P's edges rounded to the nearest
// multiple of the block side; the effective remainder is (|A Δ P| + σ |I|) / |P|.
TEST(Subperiod, BlockCoverAddsUpToTheFootprint) {
  for (const uint32_t rank : {UINT32_MAX, 1u}) {
    auto o = open_with(assets().twill, forced(FootprintBase::Blocks, rank));
    const EvalData& d = *evaluator_data(o->evaluator);
    ASSERT_TRUE(d.subperiod.is_open());
    const double side = double(d.n / d.subperiod.blocks());
    const double spread = block_interior_spread(d.subperiod.layout().rank, d.visibility_rank());
    EXPECT_EQ(spread > 0.0, rank == 1u);
    Rng rng(31);
    int with_blocks = 0, without = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const double x0 = -100 + 200 * rng.uniform(), y0 = -100 + 200 * rng.uniform();
      const double w = 0.5 + 150 * rng.uniform() * rng.uniform(), h = 0.5 + 150 * rng.uniform();
      const Footprint p{x0, y0, x0 + w, y0 + h};
      const FootprintCover cover = cover_footprint(d, p);
      if (cover.base == FootprintCover::Base::None) {
        ++without;
        ASSERT_EQ(cover.region_count, 1u);
        EXPECT_NEAR(cover.regions[0].area, w * h, 1e-12 * w * h);
        EXPECT_EQ(cover.remainder, 2.0);  // the form without a base (kWithoutBaseRemainder)
        continue;
      }
      ASSERT_EQ(cover.base, FootprintCover::Base::Blocks);
      ++with_blocks;
      const Footprint a{cover.blocks.x0 * side, cover.blocks.y0 * side, cover.blocks.x1 * side,
                        cover.blocks.y1 * side};
      for (const auto& [edge, got] :
           {std::pair{x0, a.x0}, {x0 + w, a.x1}, {y0, a.y0}, {y0 + h, a.y1}})
        EXPECT_EQ(got, std::floor(edge / side + 0.5) * side) << trial;
      const double inner = std::max(0.0, std::min(p.x1, a.x1) - std::max(p.x0, a.x0)) *
                           std::max(0.0, std::min(p.y1, a.y1) - std::max(p.y0, a.y0));
      const double a_area = (a.x1 - a.x0) * (a.y1 - a.y0);
      EXPECT_NEAR(cover.remainder, (a_area + w * h - 2 * inner + spread * inner) / (w * h),
                  1e-12 * (1 + cover.remainder));
      const double box = std::max({w, h, a.x1 - a.x0, a.y1 - a.y0}) + 2 * side + 2;
      for (int k = 0; k < 400; ++k) {
        const double x = std::min(x0, a.x0) - 1 + box * rng.uniform();
        const double y = std::min(y0, a.y0) - 1 + box * rng.uniform();
        double cg = 0, cr = inside(a, x, y) ? 1.0 : 0.0;
        for (uint32_t r = 0; r < cover.region_count; ++r) {
          const CheapRegion& region = cover.regions[r];
          if (!inside(region.rect, x, y)) continue;
          if (region.kind == CheapRegion::Kind::Difference) {
            cg += 1.0;
            cr -= 1.0;
          } else {
            ASSERT_EQ(region.kind, CheapRegion::Kind::Indicator);
            cg += inside(p, x, y) ? 1.0 : 0.0;
            cr -= inside(a, x, y) ? 1.0 : 0.0;
          }
        }
        const double want = inside(p, x, y) ? 1.0 : 0.0;
        if (spread > 0.0) {
          ASSERT_EQ(cg, want) << trial << " at " << x << ", " << y;
          ASSERT_EQ(cr, 0.0) << trial << " at " << x << ", " << y;
        } else {
          ASSERT_EQ(cg + cr, want) << trial << " at " << x << ", " << y;
        }
      }
    }
    EXPECT_GT(with_blocks, 100);
    EXPECT_GT(without, 0);
  }
}

// The block prefix sums of a view bin against an independent push-forward: s x s midpoint samples
// per source texel of a block rectangle, each moved by its bin's Eq. 2 offset and counted in the
// texel it lands in (within 2 q max|channel| / s for q source texels, as the whole-tile test); the
// whole tile's prefix point against the whole-tile push-forward sums (float storage: 1e-5).
TEST(Subperiod, BlockSumsAreTheMovedBlocks) {
  auto o = open_with(assets().twill, forced(FootprintBase::Blocks));
  const EvalData& d = *evaluator_data(o->evaluator);
  const PushforwardChannels& layout = d.subperiod.layout();
  ASSERT_EQ(layout.rank, d.visibility_rank());
  const uint32_t nb = d.subperiod.blocks(), side = d.n / nb;
  ASSERT_EQ(nb, 16u);
  ShadingFrame frame;
  Status status;
  const double wo[3] = {-0.4, 0.1, 0.85};
  ASSERT_TRUE(make_frame(d, kReflectWi, wo, kAllLobes, &frame, &status));
  const uint32_t bin = uint32_t(frame.parallax_bins.index[0]);
  const float* prefix = d.subperiod.bin_prefix(bin);
  const double* tile = d.pushforward.bin_sums(bin);
  ASSERT_NE(prefix, nullptr);
  ASSERT_NE(tile, nullptr);
  auto point = [&](uint32_t i, uint32_t j) {
    return prefix + (uint64_t(j) * (nb + 1) + i) * layout.count();
  };
  // The whole tile.
  for (uint32_t ch = 0; ch < layout.count(); ++ch)
    EXPECT_NEAR(point(nb, nb)[ch], tile[ch], 1e-5 * (std::abs(tile[ch]) + 1.0)) << ch;
  // Channels: the first image's weight, cluster 0's area with every visibility component.
  const model::DirectionGrid<double> grid{int(d.parallax.dirs()), d.parallax.info().min_cos};
  const model::Vec3d c = grid.bin_center(int(bin) % grid.n, int(bin) / grid.n);
  const double fx = d.n * c.x / c.z, fy = d.n * c.y / c.z;
  std::vector<uint32_t> channels = {layout.spec(0, 0)};
  for (uint32_t j = 0; j <= layout.rank; ++j)
    channels.push_back(layout.lobe(0, j) + 6);
  auto channel = [&](uint64_t t, uint32_t ch) {
    double e[17];
    d.visibility_coefficients(t, e);
    if (ch == layout.spec(0, 0)) {
      uint32_t first = 0;
      double w[256];
      const uint32_t count = d.specular.compressed.texel_image_weights_at(t, &first, w);
      return first == 0 && count > 0 ? w[0] : 0.0;
    }
    if (d.clusters.label_at(t) != 0) return 0.0;
    return e[(ch - layout.lobe(0, 0) - 6) / PushforwardChannels::kPerLobeGroup];
  };
  const uint32_t s = 8;
  struct Rect {
    uint32_t bx0, by0, bx1, by1;
  };
  for (const Rect& r :
       {Rect{0, 0, 1, 1}, Rect{3, 5, 4, 6}, Rect{2, 1, 7, 4}, Rect{0, nb - 3, nb, nb}}) {
    for (uint32_t ch : channels) {
      const double stored = double(point(r.bx1, r.by1)[ch]) - double(point(r.bx0, r.by1)[ch]) -
                            double(point(r.bx1, r.by0)[ch]) + double(point(r.bx0, r.by0)[ch]);
      double sampled = 0, largest = 0;
      for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t)
        largest = std::max(largest, std::abs(channel(t, ch)));
      for (uint32_t qy = r.by0 * side; qy < r.by1 * side; ++qy)
        for (uint32_t qx = r.bx0 * side; qx < r.bx1 * side; ++qx) {
          const double depth = d.parallax.bin_depth(bin, qx, qy);
          for (uint32_t b = 0; b < s; ++b)
            for (uint32_t a = 0; a < s; ++a) {
              const double x = qx + (a + 0.5) / s + depth * fx, y = qy + (b + 0.5) / s + depth * fy;
              sampled += channel(d.texel(int64_t(std::floor(x)), int64_t(std::floor(y))), ch) /
                         double(s * s);
            }
        }
      const double texels = double((r.bx1 - r.bx0) * (r.by1 - r.by0)) * side * side;
      EXPECT_GT(largest, 0.0) << "channel " << ch;
      EXPECT_LE(std::abs(stored - sampled), 2.0 * texels * largest / s + 1e-5 * d.n * d.n * largest)
          << "channel " << ch << ", blocks " << r.bx0 << "," << r.by0 << " .. " << r.bx1 << ","
          << r.by1;
    }
  }
}

// Sub-tile footprints (a block, a third of a tile, one across the tile's edge, 0.78 of a tile
// across the origin; blocks of 4 texels when forced, of 16 in the default cover's 256 MiB on the
// 64^2 fixtures): every form's mean of 4000 estimates at 2 spp within 3 standard errors of the
// reference, reflection and transmission, the twill and the satin. Slack 2e-5 relative: the block
// sums are stored as float.
void expect_unbiased_below_a_period(const std::string& asset, const EvalOptions& options,
                                    uint64_t seed, const char* what,
                                    bool texel_attenuation = false) {
  const Footprint footprints[] = {{5.3, 7.7, 9.9, 13.1},
                                  {10.2, 3.4, 31.9, 20.0},
                                  {50.5, -6.3, 81.0, 33.3},
                                  {-20.6, 12.1, 29.5, 61.7}};
  auto o = open_with(asset, options);
  if (texel_attenuation) set_texel_attenuation(*o);
  for (const Directions& dirs : kConfigurations)
    for (const Footprint& p : footprints) {
      const Stats st = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 2, 4000, seed);
      expect_mean_within_3se(st, reference(o->evaluator, p, dirs.wi, dirs.wo), 2e-5, what);
    }
}

TEST(Subperiod, IsUnbiasedBelowAPeriod) {
  EvalOptions shipped;  // the default choice, with the control variate on every footprint
  shipped.min_control_variate_side = 0.0;
  for (const std::string* asset : {&assets().twill, &assets().satin}) {
    expect_unbiased_below_a_period(*asset, forced(FootprintBase::Blocks), 41, "blocks");
    expect_unbiased_below_a_period(*asset, forced(FootprintBase::Blocks, 1), 42,
                                   "blocks of rank 1");
    expect_unbiased_below_a_period(*asset, forced(FootprintBase::None), 43, "no base");
    expect_unbiased_below_a_period(*asset, shipped, 44, "the default cover");
    expect_unbiased_below_a_period(*asset, forced(FootprintBase::None), 46,
                                   "no base, the texel's attenuation", true);
    expect_unbiased_below_a_period(*asset, shipped, 47,
                                   "the default cover, the texel's attenuation", true);
  }
}

// Threads of one yarn dyed differently (the striped twill: its warp ends in three colours, so its
// warp clusters mix colours). Without a base the control variate is g_V, which carries each
// texel's own specular albedo; with one
// (the block form, forced, on a third of the tile; whole periods on two tiles by the default
// cover; the correction in every band) the bins' sums hold the cluster's mean and the visibility
// correction's g_V carries the texel's own. Every form stays unbiased there, and its variance stays
// far below brute force's, where the cluster's mean albedo left the colour difference in the
// residual (the floors: measured in the test's output and docs/evaluator.md).
TEST(Subperiod, EveryFormFollowsDyedThreads) {
  expect_unbiased_below_a_period(assets().striped, forced(FootprintBase::None), 45,
                                 "no base, dyed warp ends");
  expect_unbiased_below_a_period(assets().striped, forced(FootprintBase::Blocks), 48,
                                 "blocks, dyed warp ends");
  struct Case {
    const char* name;
    EvalOptions options;
    Footprint footprint;
    FootprintCover::Base base;
    double floor;
  };
  // With a base the correction runs in every band (no pilot): the floors measure g_V, not the
  // pilot's choice.
  EvalOptions blocks = forced(FootprintBase::Blocks), periods;
  blocks.visibility_pilot = periods.visibility_pilot = false;
  const Footprint third{10.2, 3.4, 31.9, 24.0}, two_tiles{-7.5, 3.25, 120.5, 131.25};
  const Case cases[] = {{"no base, a third of the tile", forced(FootprintBase::None), third,
                         FootprintCover::Base::None, kDyedThreadsRatioFloor},
                        {"blocks, a third of the tile", blocks, third, FootprintCover::Base::Blocks,
                         kDyedThreadsBaseRatioFloor},
                        {"whole periods, two tiles", periods, two_tiles,
                         FootprintCover::Base::WholePeriods, kDyedThreadsBaseRatioFloor}};
  for (const Case& c : cases) {
    auto o = open_with(assets().striped, c.options);
    const Footprint& p = c.footprint;
    ASSERT_EQ(cover_footprint(*evaluator_data(o->evaluator), p).base, c.base) << c.name;
    if (c.base == FootprintCover::Base::WholePeriods)
      for (const Directions& dirs : kConfigurations)
        expect_mean_within_3se(
            repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 2, 4000, 49),
            reference(o->evaluator, p, dirs.wi, dirs.wo), 2e-5, "whole periods, dyed warp ends");
    const Stats brute = repeat(o->evaluator, p, kReflectWi, kReflectWo, Method::Brute, 2, 4000, 46);
    const Stats multiscale =
        repeat(o->evaluator, p, kReflectWi, kReflectWo, Method::Multiscale, 2, 4000, 47);
    const double ratio =
        (brute.sd_green * brute.sd_green) / (multiscale.sd_green * multiscale.sd_green);
    std::printf("dyed warp ends, %s, 2 spp: variance ratio brute / multiscale %.1f\n", c.name,
                ratio);
    EXPECT_GT(ratio, c.floor) << c.name;
  }
}

// The mutation check: the block base of the view's bins scaled by 1.03 (every stored prefix sum),
// the same comparison fails on a footprint of whole blocks; restored, it passes again.
TEST(Subperiod, UnbiasednessTestCatchesABlockBaseThreePercentOff) {
  auto o = open_with(assets().twill, forced(FootprintBase::Blocks));
  const EvalData& d = *evaluator_data(o->evaluator);
  const Footprint p{8.0, 12.0, 40.0, 36.0};
  ShadingFrame frame;
  Status status;
  ASSERT_TRUE(make_frame(d, kReflectWi, kReflectWo, kAllLobes, &frame, &status));
  const uint64_t floats = d.subperiod.bin_bytes() / sizeof(float);
  std::vector<std::vector<float>> saved;
  std::vector<float*> bins;
  for (int k = 0; k < 4; ++k) {
    if (!(frame.parallax_bins.weight[k] > 0.0)) continue;
    float* prefix =
        const_cast<float*>(d.subperiod.bin_prefix(uint32_t(frame.parallax_bins.index[k])));
    ASSERT_NE(prefix, nullptr);
    if (std::find(bins.begin(), bins.end(), prefix) != bins.end()) continue;
    bins.push_back(prefix);
    saved.emplace_back(prefix, prefix + floats);
  }
  const Rgb ref = reference(o->evaluator, p, kReflectWi, kReflectWo);
  const Stats good =
      repeat(o->evaluator, p, kReflectWi, kReflectWo, Method::Multiscale, 2, 4000, 51);
  for (float* prefix : bins)
    for (uint64_t k = 0; k < floats; ++k)
      prefix[k] *= 1.03f;
  const Stats bad =
      repeat(o->evaluator, p, kReflectWi, kReflectWo, Method::Multiscale, 2, 4000, 51);
  for (size_t b = 0; b < bins.size(); ++b)
    std::copy(saved[b].begin(), saved[b].end(), bins[b]);
  const Stats again =
      repeat(o->evaluator, p, kReflectWi, kReflectWo, Method::Multiscale, 2, 4000, 51);
  EXPECT_LE(std::abs(good.mean.mean() - ref.mean()), 3.0 * good.se.mean() + 2e-5 * ref.mean());
  EXPECT_GT(std::abs(bad.mean.mean() - ref.mean()), 3.0 * bad.se.mean() + 2e-5 * ref.mean())
      << "a 3 % error in the block base went unnoticed: mean " << bad.mean.mean() << " reference "
      << ref.mean() << " se " << bad.se.mean();
  EXPECT_EQ(again.mean.mean(), good.mean.mean());  // restored exactly, same draws
}

// Without a base the control variate is g_V, whose integral only the cheap samples estimate: the
// estimate is unbiased for any g_V, and g_V sets only its variance. With every texel's g_V record
// spoilt (half its visibility's amplitude, the lobe turned by a right angle, the colour 1.3 times
// and the gap flipped) the mean of 4000 estimates stays within 3 standard errors of the reference,
// reflection and transmission, and the variance grows at least fourfold (the variance is what g_V
// was for); restored, the estimates are the first run's bit for bit. Its power: a scratch build
// whose cheap samples took 1.03 g_V (the residual g_V) failed it, and IsUnbiasedBelowAPeriod.
TEST(Subperiod, WithoutABaseAnyControlVariateIsUnbiased) {
  auto o = open_with(assets().twill, forced(FootprintBase::None));
  const EvalData& d = *evaluator_data(o->evaluator);
  const Footprint p{10.2, 3.4, 31.9, 20.0};
  ASSERT_EQ(cover_footprint(d, p).base, FootprintCover::Base::None);
  const uint64_t texels = uint64_t(d.n) * d.n;
  std::vector<ControlVariateTexels::Exact> saved(texels);
  for (const Directions& dirs : kConfigurations) {
    const Rgb ref = reference(o->evaluator, p, dirs.wi, dirs.wo);
    const Stats good = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 2, 4000, 52);
    for (uint64_t t = 0; t < texels; ++t) {
      auto& x = const_cast<ControlVariateTexels::Exact&>(d.cv_texels.exact(t));
      saved[t] = x;
      x.amplitude *= 0.5f;
      std::swap(x.rotation[0], x.rotation[1]);
      x.rotation[1] = -x.rotation[1];
      for (float& c : x.colour)
        c *= 1.3f;
      x.gap = 1.0f - x.gap;
    }
    const Stats spoilt = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 2, 4000, 52);
    for (uint64_t t = 0; t < texels; ++t)
      const_cast<ControlVariateTexels::Exact&>(d.cv_texels.exact(t)) = saved[t];
    const Stats again = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 2, 4000, 52);
    expect_mean_within_3se(good, ref, 2e-5, "no base");
    expect_mean_within_3se(spoilt, ref, 2e-5, "no base, g_V spoilt");
    const double ratio = (spoilt.sd_green * spoilt.sd_green) / (good.sd_green * good.sd_green);
    std::printf("no base, g_V spoilt: variance %.1f times the shipped g_V's\n", ratio);
    EXPECT_GT(ratio, 4.0);
    EXPECT_EQ(again.mean.mean(), good.mean.mean());
  }
}

// With each texel's own attenuation, g_V's specular reflection is f's (Eq. 10 at the texel's
// tangent, the texel's visibility, albedo and gap) up to the float rounding of its record: the
// residual f - g_V of the form without a base vanishes, at grazing pairs as at normal ones, where
// the yarn's attenuation leaves a residual (measured: docs/evaluator.md, "The attenuation g_V
// takes").
TEST(Subperiod, TexelAttenuationMakesGVTheSpecularReflection) {
  EvalOptions options = forced(FootprintBase::None);
  options.attenuation_pilot = false;  // the yarn's
  auto texel = open_with(assets().satin, options);
  set_texel_attenuation(*texel);
  auto yarn = open_with(assets().satin, options);
  const Footprint p{10.2, 3.4, 31.9, 20.0};
  const double pairs[][6] = {{0.3, 0.2, 0.9, -0.4, 0.1, 0.85},    // near the normal
                             {0.95, 0.0, 0.15, -0.3, 0.93, 0.2},  // grazing light and view
                             {-0.6, 0.7, 0.39, 0.98, 0.0, 0.2}};  // grazing view
  for (const auto& pair : pairs) {
    double variance[2], residual[2];
    for (int own = 0; own < 2; ++own) {
      const EvalData& d = *evaluator_data((own ? texel : yarn)->evaluator);
      ShadingFrame frame;
      Status status;
      ASSERT_TRUE(make_frame(d, pair, pair + 3, lobe_bit(model::Lobe::SpecularReflection), &frame,
                             &status));
      Rng rng(9);
      Estimate estimate;
      ResidualMoments moments;
      ASSERT_TRUE(
          pushforward_control_variates(d, frame, p, no_base_cover(p), 256, rng, &estimate, &moments)
              .ok());
      variance[own] = moments.variance(ResidualMoments::kCorrectedResidual);  // f - g_V
      residual[own] = moments.variance(ResidualMoments::kResidual);           // f - g
    }
    std::printf(
        "o_z %.2f, i_z %.2f: var(f - g_V) / var(f - g) %.3g with the yarn's attenuation, "
        "%.3g with the texel's\n",
        pair[5], pair[2], variance[0] / residual[0], variance[1] / residual[1]);
    EXPECT_GT(residual[1], 0.0);
    EXPECT_LT(variance[1], 1e-9 * residual[1]);
    EXPECT_GT(variance[0], 1e3 * variance[1]);
  }
}

// The block grid is the finest (at most 16 x 16 blocks a tile, dividing N) whose sums over every
// view bin fit max_block_sum_bytes; none when even 2 x 2 does not (then no footprint takes the
// block form); its memory is spent only on the bins met.
TEST(Subperiod, BlockGridFollowsTheMemoryBudget) {
  auto full = open_with(assets().twill, EvalOptions{});
  const EvalData& d = *evaluator_data(full->evaluator);
  ASSERT_TRUE(d.subperiod.is_open());
  const double bins = double(d.parallax.dirs()) * d.parallax.dirs();
  const double channels = d.subperiod.layout().count();
  auto bytes = [&](double nb) { return (nb + 1) * (nb + 1) * channels * sizeof(float) * bins; };
  uint32_t finest = 16;  // in the default 256 MiB
  while (finest > 2 && bytes(finest) > double(uint64_t(256) << 20))
    finest /= 2;
  EXPECT_EQ(d.subperiod.blocks(), finest);
  EXPECT_EQ(d.subperiod.bin_bytes(), uint64_t(bytes(finest) / bins));
  for (const auto& [budget, want] : {std::pair{bytes(16), 16u},
                                     {bytes(16) - 1, 8u},
                                     {bytes(8), 8u},
                                     {bytes(4) - 1, 2u},
                                     {bytes(2) - 1, 0u},
                                     {0.0, 0u}}) {
    EvalOptions options;
    options.max_block_sum_bytes = budget;
    auto o = open_with(assets().twill, options);
    const EvalData& e = *evaluator_data(o->evaluator);
    EXPECT_EQ(e.subperiod.is_open(), want > 0) << budget;
    if (want > 0) {
      EXPECT_EQ(e.subperiod.blocks(), want) << budget;
    }
    if (want == 0) {
      Rng rng(5);
      for (int k = 0; k < 50; ++k) {
        const Footprint p{rng.uniform() * 64, rng.uniform() * 64, 0, 0};
        const Footprint q{p.x0, p.y0, p.x0 + 5 + 80 * rng.uniform(), p.y0 + 5 + 80 * rng.uniform()};
        EXPECT_NE(cover_footprint(e, q).base, FootprintCover::Base::Blocks);
      }
    }
  }
  EvalOptions negative;
  negative.max_block_sum_bytes = -1;
  Evaluator ev;
  EXPECT_EQ(ev.open(full->asset, negative).code(), reader::ErrorCode::InvalidArgument);
}

}  // namespace
}  // namespace clothbake::eval

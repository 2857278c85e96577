// The multi-scale evaluator (eval/evaluator.hpp) against closed forms, its own exact reference and
// the model: exactness of the reference partition, unbiasedness within standard errors, the
// variance of the unbiased control variates against brute force, and bad arguments.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "eval/eval_data.hpp"
#include "eval/evaluator.hpp"
#include "eval/footprint_cover.hpp"
#include "eval/methods.hpp"
#include "eval/texel_shading.hpp"
#include "eval/visibility_pilot.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "tests/eval/eval_fixtures.hpp"
#include "tests/eval/eval_stats.hpp"

namespace clothbake::eval {
namespace {

using namespace eval_test;
using model::Lobe;

// The smallest variance ratio the far-field test accepts (measured values in the test's output
// and docs/evaluator.md).
constexpr double kVarianceRatioFloor = 20.0;

// ---------------------------------------------------------------------------------------------
// The flat fabric: every approximation of Eq. 8-10 is exact.

// The integrand of the flat fabric at a yarn (I = 1) or gap (I = 0) texel, from the model directly.
Rgb flat_value(bool yarn, const double wi[3], const double wo[3]) {
  // The maps hold float: the tangent and the colour as the asset stores them.
  auto f = [](double v) { return double(float(v)); };
  const Rgb colour(f(0.8), f(0.6), f(0.4));
  model::TexelParams<double> p;
  p.tangent = {f(0.6), f(0.8), 0.0};
  p.roughness = 1.0;
  p.optical_thickness = 1.5;
  p.specular_albedo = Rgb(0.5) * colour;
  p.diffuse_reflectance = Rgb(0.3) * colour;
  p.diffuse_transmittance = Rgb(0.2) * colour;
  p.gap = yarn ? 1.0 : 0.0;
  p.sheen_color = Rgb(0.3);
  p.sheen_roughness = 0.5;
  const model::Vec3d i = model::normalize(model::Vec3d(wi[0], wi[1], wi[2]));
  const model::Vec3d o = model::normalize(model::Vec3d(wo[0], wo[1], wo[2]));
  const model::LobeValues<double> lobes = model::ClothBsdf<double>(p).eval(i, o, 1.0);
  Rgb v = lobes.total * std::abs(i.z);
  if (i.x == -o.x && i.y == -o.y && i.z == -o.z) v += lobes.delta_transmission;
  return v;
}

TEST(Flat, ReferenceIsTheClosedForm) {
  auto o = open(assets().flat);
  for (const Directions& dirs : kConfigurations) {
    const Rgb yarn = flat_value(true, dirs.wi, dirs.wo);
    const Rgb gap = flat_value(false, dirs.wi, dirs.wo);
    // The checker has 4 x 4 blocks, yarn at block (0, 0): a block, whole tiles, many tiles.
    const Rgb in_block = reference(o->evaluator, {0.5, 1.25, 3.5, 3.75}, dirs.wi, dirs.wo);
    const Rgb in_gap = reference(o->evaluator, {4.5, 0.25, 7.5, 3.75}, dirs.wi, dirs.wo);
    const Rgb tile = reference(o->evaluator, {-3.0, 5.0, 13.0, 21.0}, dirs.wi, dirs.wo);
    const Rgb huge =
        reference(o->evaluator, {16.0 * 7, -16.0 * 40, 16.0 * 300, 16.0 * 9}, dirs.wi, dirs.wo);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(in_block[c], yarn[c], 1e-12 * yarn[c]);
      EXPECT_NEAR(in_gap[c], gap[c], 1e-12 * yarn[c]);
      EXPECT_NEAR(tile[c], 0.5 * (yarn[c] + gap[c]), 1e-12 * yarn[c]);
      EXPECT_NEAR(huge[c], 0.5 * (yarn[c] + gap[c]), 1e-9 * yarn[c]);
    }
  }
}

TEST(Flat, DeltaLobeIsTheGapWeightAtMinusO) {
  auto o = open(assets().flat);
  const double wo[3] = {0.2, -0.1, 0.95};
  const double wi[3] = {-0.2, 0.1, -0.95};
  const Rgb tile =
      reference(o->evaluator, {0, 0, 16, 16}, wi, wo, lobe_bit(Lobe::DeltaTransmission));
  // W = V T_sheen (1 - I) on the gap half of the tile.
  model::TexelParams<double> p;
  p.sheen_color = Rgb(0.3);
  p.sheen_roughness = 0.5;
  const Rgb t_sheen = model::ClothBsdf<double>(p).sheen_transmittance(
      model::normalize(model::Vec3d(wo[0], wo[1], wo[2])));
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(tile[c], 0.5 * t_sheen[c], 1e-12);
  // Off the Dirac direction the delta lobe is 0.
  const Rgb off = reference(o->evaluator, {0, 0, 16, 16}, kTransmitWi, kTransmitWo,
                            lobe_bit(Lobe::DeltaTransmission));
  EXPECT_EQ(off.g, 0.0);
  // Every method agrees: the multi-scale ones from the gap table, exactly.
  for (Method m : {Method::Multiscale, Method::MultiscalePaper}) {
    const Stats st = repeat(o->evaluator, {0.3, 0.6, 15.3, 14.6}, wi, wo, m, 2, 50, 9,
                            lobe_bit(Lobe::DeltaTransmission));
    const Rgb ref =
        reference(o->evaluator, {0.3, 0.6, 15.3, 14.6}, wi, wo, lobe_bit(Lobe::DeltaTransmission));
    expect_within_3se(st, ref, 1e-6, method_name(m));
  }
}

TEST(Flat, EveryMethodAgreesInExpectation) {
  auto o = open(assets().flat);
  const Footprint footprints[] = {{2.2, 5.1, 3.2, 6.1},
                                  {1.5, 2.5, 5.5, 6.5},
                                  {0.3, 0.7, 32.3, 32.7},
                                  {0, 0, 16, 16},
                                  {-40.5, 9.25, 200.5, 150.75}};
  for (const Directions& dirs : kConfigurations)
    for (const Footprint& p : footprints) {
      const Rgb ref = reference(o->evaluator, p, dirs.wi, dirs.wo);
      for (Method m : {Method::Multiscale, Method::MultiscalePaper, Method::Brute}) {
        const Stats st = repeat(o->evaluator, p, dirs.wi, dirs.wo, m, 2, 400, 17);
        // The raw tables' fixed-point quantisation is far below 1e-6 of the value.
        expect_within_3se(st, ref, 1e-6, method_name(m));
      }
    }
}

// ---------------------------------------------------------------------------------------------
// The integrand itself.

TEST(TexelShading, IsTheModelWithTheTexelsParametersAndTheStoredVisibility) {
  auto o = open(assets().twill);
  const EvalData& d = *evaluator_data(o->evaluator);
  reader::VisibilityAsgView visibility;
  ASSERT_TRUE(visibility.open(o->asset).ok());
  Rng rng(5);
  for (int k = 0; k < 500; ++k) {
    const double wi[3] = {rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() * 2 - 1};
    const double wo[3] = {rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() * 2 - 1};
    ShadingFrame frame;
    Status s;
    ASSERT_TRUE(make_frame(d, wi, wo, kAllLobes, &frame, &s));
    const int64_t x = int64_t(rng.uniform() * 64), y = int64_t(rng.uniform() * 64);
    TexelShading shading;
    shade_texel(d, frame, x, y, &shading);
    // V as `clothbake query visibility` reports it, for the light mirrored onto the upper side.
    const double light[3] = {frame.wi.x, frame.wi.y, std::abs(frame.wi.z)};
    double v = 0;
    ASSERT_TRUE(visibility.visibility(x, y, light, &v).ok());
    EXPECT_NEAR(shading.visibility, v, 1e-14);  // the reader normalises the unit vector again
    const model::LobeValues<double> f =
        model::ClothBsdf<double>(d.texel_params(d.texel(x, y))).eval(frame.wi, frame.wo, v);
    for (int l = 0; l < model::kLobeCount; ++l) {
      if (Lobe(l) == Lobe::DeltaTransmission) continue;
      const Rgb want = f[Lobe(l)] * std::abs(frame.wi.z);
      // The same model on the same numbers, up to the rounding of separately compiled code.
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(shading.lobes[l][c], want[c], 1e-13 * want[c]);
    }
    EXPECT_EQ(shading.lobes[int(Lobe::DeltaTransmission)].g, 0.0);  // i != -o
  }
}

TEST(TexelShading, ColourTintsTheYarnAlbedos) {
  auto o = open(assets().twill);
  const EvalData& d = *evaluator_data(o->evaluator);
  for (uint64_t t : {uint64_t(0), uint64_t(1000), uint64_t(4095)}) {
    const model::TexelParams<double> p = d.texel_params(t);
    const YarnShading& yarn = d.yarns[d.maps.yarn_id[t]];
    const double colour = d.maps.albedo[3 * t + 1];
    EXPECT_EQ(p.specular_albedo.g, yarn.specular_albedo.g * colour);
    EXPECT_EQ(p.diffuse_reflectance.g, yarn.diffuse_reflectance.g * colour);
    EXPECT_EQ(p.diffuse_transmittance.g, yarn.diffuse_transmittance.g * colour);
    EXPECT_EQ(p.gap, d.maps.gap[t]);
  }
}

// ---------------------------------------------------------------------------------------------
// The reference.

TEST(Reference, SupersamplingConvergesToTheExactPartitionWithinItsBound) {
  auto o = open(assets().twill);
  const EvalData& d = *evaluator_data(o->evaluator);
  const Footprint footprints[] = {{10.3, 20.7, 11.3, 21.7},
                                  {5.5, 7.25, 9.5, 11.25},
                                  {3.1, 40.2, 35.1, 72.2},
                                  {-17.5, 3.3, 100.5, 90.7}};
  for (const Directions& dirs : kConfigurations) {
    // The bound |Q_s - exact| <= max_t g(t) / s (docs/evaluator.md, "Reference"), per channel.
    ShadingFrame frame;
    Status s;
    ASSERT_TRUE(make_frame(d, dirs.wi, dirs.wo, kAllLobes, &frame, &s));
    Rgb g_max;
    for (int64_t y = 0; y < 64; ++y)
      for (int64_t x = 0; x < 64; ++x) {
        TexelShading shading;
        shade_texel(d, frame, x, y, &shading);
        Rgb g;
        for (const Rgb& lobe : shading.lobes)
          g += lobe;
        for (int c = 0; c < 3; ++c)
          if (g[c] > g_max[c]) (c == 0 ? g_max.r : c == 1 ? g_max.g : g_max.b) = g[c];
      }
    for (const Footprint& p : footprints) {
      const Rgb exact = reference(o->evaluator, p, dirs.wi, dirs.wo);
      double previous = -1;
      for (uint32_t ss : {2u, 4u, 8u, 16u, 32u}) {
        Estimate e;
        ASSERT_TRUE(
            o->evaluator.reference_supersampled(p, dirs.wi, dirs.wo, ss, kAllLobes, &e).ok());
        for (int c = 0; c < 3; ++c)
          EXPECT_LE(std::abs(e.value[c] - exact[c]), g_max[c] / ss);
        if (previous >= 0) {
          // Doubling the supersampling changes the value by less than the two bounds.
          EXPECT_LE(std::abs(e.value.g - previous), g_max.g / ss + 2 * g_max.g / ss);
        }
        previous = e.value.g;
      }
    }
  }
}

TEST(Reference, WholeTileMultiplesAreThePeriodicAverage) {
  auto o = open(assets().twill);
  const Rgb tile = reference(o->evaluator, {0, 0, 64, 64}, kReflectWi, kReflectWo);
  const Rgb shifted =
      reference(o->evaluator, {64 * 5, -64 * 3, 64 * 6, -64 * 2}, kReflectWi, kReflectWo);
  const Rgb many =
      reference(o->evaluator, {-64 * 30, 64 * 2, 64 * 34, 64 * 66}, kReflectWi, kReflectWo);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(shifted[c], tile[c], 1e-13 * tile[c]);
    EXPECT_NEAR(many[c], tile[c], 1e-11 * tile[c]);
  }
}

TEST(Reference, BruteForceIsUnbiasedForIt) {
  auto o = open(assets().twill);
  const Footprint footprints[] = {{10.3, 20.7, 11.3, 21.7}, {3.1, 40.2, 35.1, 72.2}};
  for (const Directions& dirs : kConfigurations)
    for (const Footprint& p : footprints) {
      const Stats st = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Brute, 16, 2000, 3);
      expect_within_3se(st, reference(o->evaluator, p, dirs.wi, dirs.wo), 0.0, "brute");
    }
}

TEST(Reference, LobesAddUpAndTheMaskRestricts) {
  auto o = open(assets().twill);
  const Footprint p{5.5, 7.25, 19.5, 21.25};
  const Rgb all = reference(o->evaluator, p, kReflectWi, kReflectWo);
  Rgb sum;
  for (int l = 0; l < model::kLobeCount; ++l) {
    Rng rng(1);
    Estimate e;
    ASSERT_TRUE(
        o->evaluator
            .estimate(p, kReflectWi, kReflectWo, Method::Reference, 1, rng, lobe_bit(Lobe(l)), &e)
            .ok());
    for (int m = 0; m < model::kLobeCount; ++m)
      if (m != l) {
        EXPECT_EQ(e.lobes[m].g, 0.0);
      }
    sum += e.value;
  }
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(sum[c], all[c], 1e-14);
}

// ---------------------------------------------------------------------------------------------
// The multi-scale methods.

// One texel (sampled as brute force), 4^2 and 32^2 (below a period), a tile, a tile and a half by
// two (whole periods plus the remainder's cheap samples), several whole tiles; reflection and
// transmission; the compressed tables (the estimator's images): the mean of 4000 estimates at 2 spp
// within 3 standard errors of the reference.
void expect_multiscale_unbiased(const std::string& asset, uint64_t seed) {
  // 1 (brute force), 4^2 and 32^2 texels (below a period), a tile, 1.5 x 2 and 3 x 2 tiles (A
  // inside P), 0.8 x 1.7 tiles (A beyond P in both axes: both rectangles subtracted) and 1.3 x 1.8
  // tiles (a column added, a row subtracted) on the 64^2 fixtures.
  const Footprint footprints[] = {{10.3, 20.7, 11.3, 21.7},  {5.5, 7.25, 9.5, 11.25},
                                  {3.1, 40.2, 35.1, 72.2},   {0, 0, 64, 64},
                                  {-10.3, 5.7, 86.2, 133.9}, {3.0, -7.0, 195.0, 121.0},
                                  {7.4, 3.3, 58.6, 112.1},   {-20.1, 11.9, 63.1, 127.1}};
  auto o = open(asset, TableChoice::Compressed);
  for (const Directions& dirs : kConfigurations)
    for (const Footprint& p : footprints) {
      const Stats st = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 2, 4000, seed);
      // The push-forward sums and the tables are summed in double from float values.
      expect_mean_within_3se(st, reference(o->evaluator, p, dirs.wi, dirs.wo), 1e-6, "multiscale");
    }
}

TEST(Multiscale, IsUnbiasedOnTheTwill) {
  expect_multiscale_unbiased(assets().twill, 11);
}

// A glossy satin: its specular lobe is narrow and its floats long, so the residual is heavy-tailed
// where the control variate misses.
TEST(Multiscale, IsUnbiasedOnTheSatin) {
  expect_multiscale_unbiased(assets().satin, 12);
}

// The visibility correction (EvalOptions::visibility_samples, docs/evaluator.md): the residual
// against g with the texel's own visibility V, and g_V - g (v the low-rank visibility) integrated
// by its own samples. Unbiased without it and at 1 and 8 samples per residual sample, for a light
// that grazes the satin (where the low-rank v misses V most) and the front light of the other
// tests; at the grazing light the correction removes most of the estimate's variance (measured on
// the 64^2 satin: the variance ratio in the test's output); and it counts its samples.
TEST(Multiscale, VisibilityCorrectionIsUnbiasedAndTightensGrazingLight) {
  const double grazing_wi[3] = {0.95, 0.2, 0.12};
  const double mirror_wo[3] = {-0.7, -0.1, 0.7};
  const Directions cases[] = {{grazing_wi, mirror_wo}, {kReflectWi, kReflectWo}};
  const Footprint footprints[] = {
      {0, 0, 64, 64}, {-10.3, 5.7, 86.2, 133.9}, {3.1, 40.2, 35.1, 72.2}};
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(assets().satin.c_str()).ok());
  double sd[3][2] = {};  // [samples 0, 1, 8][case]: the grazing case, a tile
  const uint32_t settings[] = {0, 1, 8};
  for (int k = 0; k < 3; ++k) {
    EvalOptions options;
    options.tables = TableChoice::Compressed;
    options.visibility_samples = settings[k];
    options.visibility_pilot = false;  // the correction in every band: what this test measures
    Evaluator ev;
    ASSERT_TRUE(ev.open(asset, options).ok());
    for (int d = 0; d < 2; ++d)
      for (const Footprint& p : footprints) {
        const Stats st =
            repeat(ev, p, cases[d].wi, cases[d].wo, Method::Multiscale, 2, 4000, 31 + k);
        expect_mean_within_3se(st, reference(ev, p, cases[d].wi, cases[d].wo), 1e-6,
                               "multiscale with visibility_samples " + std::to_string(settings[k]));
        if (p.x0 == 0) sd[k][d] = st.sd_green;
      }
    Rng rng(5);
    Estimate e;
    ASSERT_TRUE(ev.estimate(footprints[0], kReflectWi, kReflectWo, Method::Multiscale, 3, rng,
                            kAllLobes, &e)
                    .ok());
    EXPECT_EQ(e.counters.visibility_samples, settings[k] * 3);
    // Where g_V takes the texel's own attenuation (the 64^2 satin's pilot takes it at the grazing
    // light's band), twice the samples.
    const bool texel = evaluator_data(ev)->texel_attenuation(grazing_wi[2]);
    ASSERT_TRUE(
        ev.estimate(footprints[0], grazing_wi, mirror_wo, Method::Multiscale, 3, rng, kAllLobes, &e)
            .ok());
    EXPECT_TRUE(texel);
    EXPECT_EQ(e.counters.visibility_samples, settings[k] * 6);
  }
  const double grazing_ratio = (sd[0][0] * sd[0][0]) / (sd[2][0] * sd[2][0]);
  std::printf(
      "variance ratio without / with 8 visibility samples, a satin tile at 2 spp: grazing "
      "light %.2f, front light %.2f\n",
      grazing_ratio, (sd[0][1] * sd[0][1]) / (sd[2][1] * sd[2][1]));
  EXPECT_GT(grazing_ratio, 2.0);
  EvalOptions too_many;
  too_many.visibility_samples = 1025;
  Evaluator refused;
  EXPECT_EQ(refused.open(asset, too_many).code(), reader::ErrorCode::InvalidArgument);
}

// The visibility pilot (eval/visibility_pilot.hpp) against an independent measurement of what it
// estimates: per band of |i_z|, 96 whole-tile estimates of another seed, the median of their
// ratios (V_2 + V_3 / kappa_V) / V_1 of an estimate's variance with the correction to without. A
// band measured below 0.5 must keep the correction and one above 0.85 must drop it (the pilot
// decides at 2/3); between, the pilot's 64 estimates may go either way. On the 64^2 satin,
// kappa_V = 8 pays (V_2 is a few percent of V_1) and kappa_V = 1 does not (V_3, about V_1, is no
// longer divided away), so both decisions are exercised. Then the plumbing, with each band's
// decision forced both ways: a whole tile (with a base) is bit for bit the estimate of the
// correction everywhere where the decision keeps it and of visibility_samples = 0 where it drops
// it, the generator's draws included; a 12^2 footprint (no base, whose control variate is g_V and
// which never corrects) is bit for bit both.
TEST(Multiscale, VisibilityPilotKeepsTheCorrectionWhereItPays) {
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(assets().satin.c_str()).ok());
  int kept = 0, dropped = 0;
  for (const uint32_t kappa : {8u, 1u}) {
    EvalOptions options;
    options.tables = TableChoice::Compressed;
    options.visibility_samples = kappa;
    Evaluator piloted, everywhere, nowhere;
    ASSERT_TRUE(piloted.open(asset, options).ok());
    options.visibility_pilot = false;
    ASSERT_TRUE(everywhere.open(asset, options).ok());
    options.visibility_samples = 0;
    ASSERT_TRUE(nowhere.open(asset, options).ok());
    const EvalData& d = *evaluator_data(everywhere);
    const EvalData& pilot = *evaluator_data(piloted);
    Rng rng(77);
    for (int band = 0; band < EvalData::kVisibilityBands; ++band) {
      std::vector<double> ratios;
      double wi[3], wo[3];
      for (int e = 0; e < 96; ++e) {
        const double z = std::max(0.02, (band + rng.uniform()) / EvalData::kVisibilityBands);
        const double phi = 6.283185307179586 * rng.uniform();
        const double zo = 0.2 + 0.8 * rng.uniform(), phio = 6.283185307179586 * rng.uniform();
        const double r = std::sqrt(1 - z * z), ro = std::sqrt(1 - zo * zo);
        wi[0] = r * std::cos(phi), wi[1] = r * std::sin(phi), wi[2] = z;
        wo[0] = ro * std::cos(phio), wo[1] = ro * std::sin(phio), wo[2] = zo;
        ShadingFrame frame;
        Status status;
        ASSERT_TRUE(make_frame(d, wi, wo, kAllLobes, &frame, &status));
        const double x = 64 * rng.uniform(), y = 64 * rng.uniform();
        const Footprint p{x, y, x + 64, y + 64};
        Estimate estimate;
        eval::ResidualMoments mo;
        ASSERT_TRUE(eval::pushforward_control_variates(d, frame, p, eval::no_base_cover(p), 8, rng,
                                                       &estimate, &mo)
                        .ok());
        ASSERT_EQ(mo.count, 8.0);
        using M = eval::ResidualMoments;
        ratios.push_back(
            (mo.variance(M::kCorrectedResidual) + mo.variance(M::kCorrection) / kappa) /
            mo.variance(M::kResidual));
      }
      std::sort(ratios.begin(), ratios.end());
      const double ratio = ratios[ratios.size() / 2];
      const bool pays = pilot.visibility_pays[band];
      std::printf("kappa_V %u, |i_z| band %d: measured ratio %.3f, pilot %s\n", kappa, band, ratio,
                  pays ? "keeps" : "drops");
      if (ratio < 0.5) {
        EXPECT_TRUE(pays) << kappa << " " << band;
      }
      if (ratio > 0.85) {
        EXPECT_FALSE(pays) << kappa << " " << band;
      }
      kept += ratio < 0.5;
      dropped += ratio > 0.85;
      // The plumbing, at the last directions of the band (their |i_z| is in it).
      const Footprint tile{0, 0, 64, 64}, small{5.5, 7.25, 17.5, 19.25};
      ASSERT_EQ(cover_footprint(d, tile).base, FootprintCover::Base::WholePeriods);
      ASSERT_EQ(cover_footprint(d, small).base, FootprintCover::Base::None);
      EvalData& decisions = const_cast<EvalData&>(pilot);
      const bool chosen = pilot.visibility_pays[band];
      for (const bool keeps : {true, false}) {
        decisions.visibility_pays[band] = keeps;
        for (uint64_t seed = 1; seed <= 4; ++seed) {
          Rng a(seed), b(seed), c(seed), e(seed), f(seed);
          Estimate with, expected, small_with, small_everywhere, small_nowhere;
          ASSERT_TRUE(
              piloted.estimate(tile, wi, wo, Method::Multiscale, 2, a, kAllLobes, &with).ok());
          ASSERT_TRUE((keeps ? everywhere : nowhere)
                          .estimate(tile, wi, wo, Method::Multiscale, 2, b, kAllLobes, &expected)
                          .ok());
          EXPECT_EQ(with.value.g, expected.value.g) << kappa << " " << band << " " << keeps;
          EXPECT_EQ(a.next(), b.next());
          ASSERT_TRUE(
              piloted.estimate(small, wi, wo, Method::Multiscale, 2, c, kAllLobes, &small_with)
                  .ok());
          ASSERT_TRUE(
              everywhere
                  .estimate(small, wi, wo, Method::Multiscale, 2, e, kAllLobes, &small_everywhere)
                  .ok());
          ASSERT_TRUE(
              nowhere.estimate(small, wi, wo, Method::Multiscale, 2, f, kAllLobes, &small_nowhere)
                  .ok());
          EXPECT_EQ(small_with.value.g, small_everywhere.value.g);
          EXPECT_EQ(small_with.value.g, small_nowhere.value.g);
          EXPECT_EQ(small_with.counters.visibility_samples, 0u);
          const uint64_t after = c.next();
          EXPECT_EQ(after, e.next());
          EXPECT_EQ(after, f.next());
        }
      }
      decisions.visibility_pays[band] = chosen;
    }
  }
  EXPECT_GE(kept, 2);
  EXPECT_GE(dropped, 2);
}

// g_V's attenuation pilot: per band of min(|i_z|, |o_z|), with more pairs and repeats than the
// pilot's (96 x 16 against 24 x 8, the same footprint sizes, common random numbers), the summed
// relative variance of forced Texel estimates times 1.25 against forced Yarn ones; where that ratio
// is clear (below 0.6 or above 1.5) the pilot must have chosen the same. The plumbing: with a
// band's decision set either way, the piloted evaluator's estimates are the forced evaluator's, bit
// for bit, at a pair in the band.
TEST(Multiscale, AttenuationPilotChoosesWhereItPays) {
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(assets().satin.c_str()).ok());
  EvalOptions options;
  options.tables = TableChoice::Compressed;
  Evaluator piloted, yarn, texel;
  ASSERT_TRUE(piloted.open(asset, options).ok());
  options.attenuation_pilot = false;  // the yarn's everywhere
  ASSERT_TRUE(yarn.open(asset, options).ok());
  ASSERT_TRUE(texel.open(asset, options).ok());
  for (bool& pays : const_cast<EvalData*>(evaluator_data(texel))->attenuation_pays)
    pays = true;
  const EvalData& pilot = *evaluator_data(piloted);
  const EvalData* forced[2] = {evaluator_data(yarn), evaluator_data(texel)};
  const uint32_t n = pilot.n;
  Rng rng(78);
  int clear = 0;
  for (int band = 0; band < EvalData::kAttenuationBands; ++band) {
    const double z0 = std::max(0.05, double(band) / EvalData::kAttenuationBands);
    const double z1 = double(band + 1) / EvalData::kAttenuationBands;
    double wi[3], wo[3], weighted[2] = {0.0, 0.0};
    for (int e = 0; e < 96; ++e) {
      const double za = z0 + (z1 - z0) * rng.uniform(), zb = z0 + (1.0 - z0) * rng.uniform();
      const double pa = 6.283185307179586 * rng.uniform(), pb = 6.283185307179586 * rng.uniform();
      const bool light_first = rng.uniform() < 0.5;
      double* a = light_first ? wi : wo;
      double* b = light_first ? wo : wi;
      a[0] = std::sqrt(1 - za * za) * std::cos(pa), a[1] = std::sqrt(1 - za * za) * std::sin(pa);
      a[2] = za;
      b[0] = std::sqrt(1 - zb * zb) * std::cos(pb), b[1] = std::sqrt(1 - zb * zb) * std::sin(pb);
      b[2] = zb;
      const double side = n * (e % 3 == 0 ? 0.15 : e % 3 == 1 ? 0.3 : 0.5);
      const double x = n * rng.uniform(), y = n * rng.uniform();
      const Footprint p{x, y, x + side, y + side};
      double sum[2] = {0.0, 0.0}, square[2] = {0.0, 0.0};
      const Rng points = rng;
      for (int own = 0; own < 2; ++own) {
        ShadingFrame frame;
        Status status;
        ASSERT_TRUE(make_frame(*forced[own], wi, wo, kAllLobes, &frame, &status));
        rng = points;
        for (int r = 0; r < 16; ++r) {
          Estimate estimate;
          ASSERT_TRUE(eval::pushforward_control_variates(*forced[own], frame, p,
                                                         eval::no_base_cover(p), 2, rng, &estimate)
                          .ok());
          double value = 0.0;
          for (const Rgb& lobe : estimate.lobes)
            value += lobe.mean();
          sum[own] += value;
          square[own] += value * value;
        }
      }
      const double mean = (sum[0] + sum[1]) / 32.0;
      if (!(mean > 0.0)) continue;
      for (int own = 0; own < 2; ++own)
        weighted[own] += (square[own] - sum[own] * sum[own] / 16.0) / (15.0 * mean * mean);
    }
    const double ratio = 1.25 * weighted[1] / weighted[0];
    const bool chosen = pilot.attenuation_pays[band];
    std::printf("min(|i_z|, |o_z|) band %d: measured ratio %.3f, pilot takes the %s's\n", band,
                ratio, chosen ? "texel" : "yarn");
    if (ratio < 0.6) {
      EXPECT_TRUE(chosen) << band;
      ++clear;
    }
    if (ratio > 1.5) {
      EXPECT_FALSE(chosen) << band;
      ++clear;
    }
    // The plumbing, at the band's last pair.
    EvalData& decisions = const_cast<EvalData&>(pilot);
    const Footprint small{5.5, 7.25, 17.5, 19.25};
    for (const bool own : {false, true}) {
      decisions.attenuation_pays[band] = own;
      for (uint64_t seed = 1; seed <= 3; ++seed) {
        Rng a(seed), b(seed);
        Estimate with, expected;
        ASSERT_TRUE(
            piloted.estimate(small, wi, wo, Method::Multiscale, 2, a, kAllLobes, &with).ok());
        ASSERT_TRUE((own ? texel : yarn)
                        .estimate(small, wi, wo, Method::Multiscale, 2, b, kAllLobes, &expected)
                        .ok());
        EXPECT_EQ(with.value.g, expected.value.g) << band << " " << own;
      }
    }
    decisions.attenuation_pays[band] = chosen;
  }
  EXPECT_GE(clear, 1);
}

// A remainder so thin that the sample count formula asks for one cheap sample (|B|/|P| = 1.5 % at
// 1 spp) while both of B's rectangles have an area: each still gets one (with one in the column
// only, the row's integral of g was dropped: a bias of about half the remainder's share).
TEST(Multiscale, IsUnbiasedWithAThinRemainder) {
  auto o = open(assets().twill, TableChoice::Compressed);
  const Footprint p{0.25, 0.5, 64.75, 65.0};
  for (const Directions& dirs : kConfigurations) {
    const Stats st = repeat(o->evaluator, p, dirs.wi, dirs.wo, Method::Multiscale, 1, 8000, 13);
    expect_mean_within_3se(st, reference(o->evaluator, p, dirs.wi, dirs.wo), 1e-6, "multiscale");
  }
  const eval::FootprintCover cover = eval::cover_footprint(*evaluator_data(o->evaluator), p);
  EXPECT_EQ(cover.base, eval::FootprintCover::Base::WholePeriods);
  EXPECT_EQ(eval::remainder_samples(*evaluator_data(o->evaluator), cover, 1), 2u);
}

// The block of whole periods and its two signed rectangles add up to the footprint, point by
// point (1_P = 1_A + sum_r sign_r 1_rect_r on a grid of test points over a box around both), and
// the block is the one of least symmetric difference among the floor and ceiling counts.
TEST(Multiscale, PeriodBlockAndItsSignedRectanglesAreTheFootprint) {
  const uint32_t n = 64;
  Rng rng(21);
  auto inside = [](const Footprint& r, double x, double y) {
    return x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
  };
  for (int trial = 0; trial < 200; ++trial) {
    const double x0 = -100 + 200 * rng.uniform(), y0 = -100 + 200 * rng.uniform();
    const double w = 1 + 300 * rng.uniform(), h = 1 + 300 * rng.uniform();
    const Footprint p{x0, y0, x0 + w, y0 + h};
    const eval::PeriodBlock b = eval::period_block(n, p);
    ASSERT_GE(b.kx, 1.0);
    ASSERT_GE(b.ky, 1.0);
    const Footprint a{x0, y0, x0 + b.kx * n, y0 + b.ky * n};
    EXPECT_NEAR(b.kx * b.ky * n * n + b.signs[0] * b.areas[0] + b.signs[1] * b.areas[1], w * h,
                1e-9 * w * h);
    double least = 1e300;
    for (double kx : {std::floor(w / n), std::ceil(w / n)})
      for (double ky : {std::floor(h / n), std::ceil(h / n)}) {
        kx = std::max(kx, 1.0);
        ky = std::max(ky, 1.0);
        least = std::min(least,
                         kx * ky * n * n + w * h - 2 * std::min(kx * n, w) * std::min(ky * n, h));
      }
    EXPECT_NEAR(b.remainder * w * h, least, 1e-9 * w * h);
    const double size = std::max({w, h, b.kx * n, b.ky * n}) + 2;
    for (int k = 0; k < 400; ++k) {
      const double x = x0 - 1 + size * rng.uniform(), y = y0 - 1 + size * rng.uniform();
      double sum = inside(a, x, y) ? 1.0 : 0.0;
      for (int r = 0; r < 2; ++r)
        if (b.areas[r] > 0.0 && inside(b.rects[r], x, y)) sum += b.signs[r];
      ASSERT_EQ(sum, inside(p, x, y) ? 1.0 : 0.0) << trial << " at " << x << ", " << y;
    }
  }
}

TEST(Multiscale, NeedsTheCompressedTables) {
  auto o = open(assets().twill, TableChoice::Raw);
  Rng rng(1);
  Estimate e;
  const Status s = o->evaluator.estimate({0, 0, 64, 64}, kReflectWi, kReflectWo, Method::Multiscale,
                                         2, rng, kAllLobes, &e);
  EXPECT_EQ(s.code(), reader::ErrorCode::NotFound);
  EXPECT_NE(std::string(s.message()).find("compressed"), std::string::npos);
  EXPECT_TRUE(o->evaluator
                  .estimate({0, 0, 64, 64}, kReflectWi, kReflectWo, Method::MultiscalePaper, 2, rng,
                            kAllLobes, &e)
                  .ok());
}

TEST(Multiscale, SmallFootprintsAreSummedExactly) {
  auto o = open(assets().twill);
  const Footprint p{10.3, 20.7, 10.9, 21.2};
  const Rgb ref = reference(o->evaluator, p, kReflectWi, kReflectWo);
  for (Method m : {Method::Multiscale, Method::MultiscalePaper}) {
    Rng rng(2);
    Estimate e;
    ASSERT_TRUE(o->evaluator.estimate(p, kReflectWi, kReflectWo, m, 2, rng, kAllLobes, &e).ok());
    EXPECT_TRUE(e.counters.direct);
    EXPECT_EQ(e.counters.samples, 0u);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(e.value[c], ref[c]);
  }
}

// A footprint below min_control_variate_side (2 texels) a side is sampled exactly as brute force
// (bit for bit with the same generator); otherwise the control variate is used: whole periods or
// blocks where they leave at most max_remainder_fraction of it to cheap samples, the form without a
// base (cheap samples of g_V, no table query) beyond, the remainder with its cheap samples; the
// paper form always has its control variate.
TEST(Multiscale, FootprintsTheControlVariateDoesNotPayForAreSampledAsBruteForce) {
  auto o = open(assets().twill);
  EvalOptions strict;
  strict.max_remainder_fraction = 0.0;  // any remainder: no base
  Evaluator samples_only;
  ASSERT_TRUE(samples_only.open(o->asset, strict).ok());
  const double wo[3] = {-0.4, 0.1, 0.85};
  const Footprint small{3.5, 9.25, 5.0, 11.25},  // 1.5 x 2: below 2 texels a side
      just_above{3.5, 9.25, 5.75, 11.25},        // 2.25 x 2
      narrow{3.5, 9.25, 30.0, 300.0},            // tall, under half the tile wide
      whole{-10.0, 5.0, 118.0, 69.0},            // two tiles by one: no remainder
      ragged{-10.0, 5.0, 120.5, 90.0},           // whole periods and a remainder
      near_tile{-3.0, 2.0, 49.0, 54.0};          // 0.81 x 0.81 tiles
  const EvalData& d = *evaluator_data(o->evaluator);
  EXPECT_EQ(cover_footprint(d, ragged).base, FootprintCover::Base::WholePeriods);
  EXPECT_EQ(cover_footprint(*evaluator_data(samples_only), ragged).base,
            FootprintCover::Base::None);
  for (int k = 0; k < 20; ++k) {
    Rng a(100 + k), b(100 + k);
    Estimate ms, brute;
    ASSERT_TRUE(
        o->evaluator.estimate(small, kReflectWi, wo, Method::Multiscale, 2, a, kAllLobes, &ms)
            .ok());
    ASSERT_TRUE(
        o->evaluator.estimate(small, kReflectWi, wo, Method::Brute, 2, b, kAllLobes, &brute).ok());
    EXPECT_TRUE(ms.counters.without_control_variate);
    EXPECT_FALSE(brute.counters.without_control_variate);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(ms.value[c], brute.value[c]);
    for (const Evaluator* ev : {&o->evaluator, &samples_only})
      for (const Footprint& p : {just_above, narrow, near_tile, ragged}) {
        ASSERT_TRUE(ev->estimate(p, kReflectWi, wo, Method::Multiscale, 2, a, kAllLobes, &ms).ok());
        EXPECT_FALSE(ms.counters.without_control_variate);
        EXPECT_GT(ms.counters.remainder_samples, 0u);
        if (ev == &samples_only) {
          EXPECT_EQ(ms.counters.table_queries, 0u);
        }
      }
    ASSERT_TRUE(
        o->evaluator.estimate(whole, kReflectWi, wo, Method::Multiscale, 2, a, kAllLobes, &ms)
            .ok());
    EXPECT_FALSE(ms.counters.without_control_variate);
    EXPECT_EQ(ms.counters.remainder_samples, 0u);
    EXPECT_GT(ms.counters.table_queries, 0u);
  }
  Rng rng(1);
  Estimate paper;
  ASSERT_TRUE(
      o->evaluator
          .estimate(small, kReflectWi, wo, Method::MultiscalePaper, 2, rng, kAllLobes, &paper)
          .ok());
  EXPECT_FALSE(paper.counters.without_control_variate);
  EXPECT_GT(paper.counters.table_queries, 0u);
}

// The control variate's packed records hold, texel by texel, exactly what the asset's views give:
// the label, the yarn, the gap and colour, the visibility coefficients and the compressed tables'
// image weights (cv_texels.hpp). g at a sample reads only the record; g_V only its own record,
// checked here against the views too.
TEST(Multiscale, TexelRecordsAreTheViewsValues) {
  for (const std::string* path : {&assets().twill, &assets().satin}) {
    auto o = open(*path);
    const EvalData& d = *evaluator_data(o->evaluator);
    const ControlVariateTexels& records = d.cv_texels;
    ASSERT_FALSE(records.empty());
    ASSERT_EQ(records.rank(), d.visibility_rank());
    ASSERT_EQ(records.stride() % 16, 0u);
    ASSERT_EQ(reinterpret_cast<std::uintptr_t>(records.address(0)) % 64, 0u);
    uint32_t widest = 0;
    ShadingFrame grazing, slanted, overhead;
    const ShadingFrame* frames[3] = {&grazing, &slanted, &overhead};
    const double lights[3][3] = {{0.97, 0.1, 0.22}, {-0.4, 0.5, 0.77}, {0.0, 0.05, 1.0}};
    for (int k = 0; k < 3; ++k) {
      Status status;
      ASSERT_TRUE(make_frame(d, lights[k], kReflectWo, kAllLobes,
                             const_cast<ShadingFrame*>(frames[k]), &status));
    }
    for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t) {
      const ControlVariateTexels::Header& h = records.header(t);
      EXPECT_EQ(h.label, d.clusters.label_at(t));
      EXPECT_EQ(h.yarn, d.maps.yarn_id[t]);
      EXPECT_EQ(h.gap, d.maps.gap[t]);
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(h.colour[c], d.maps.albedo.data[3 * t + c]);
      double e[17];
      d.visibility_coefficients(t, e);
      for (uint32_t j = 0; j < records.rank(); ++j)
        EXPECT_EQ(double(records.coefficients(t)[j]), e[j + 1]);
      uint32_t first = 0;
      double w[256];
      const uint32_t count = d.specular.compressed.texel_image_weights_at(t, &first, w);
      ASSERT_EQ(h.count, count);
      if (count > 0) {
        EXPECT_EQ(h.first_image, first);
      }
      for (uint32_t j = 1; j < count; ++j)
        EXPECT_EQ(double(records.image_weights(t)[j - 1]), w[j]);
      widest = std::max(widest, count);
      // g_V's record: the lobe decoded as the reader decodes it (its visibility at three lights,
      // the record's own evaluation that g_V calls, against texel_visibility within the float
      // rounding), the unit
      // tangent, the gap as model::ClothBsdf reads it, the colour, the yarn and the cluster of the
      // cell's first image.
      const ControlVariateTexels::Exact& x = records.exact(t);
      for (const ShadingFrame* frame : frames)
        EXPECT_NEAR(x.visibility(frame->wi_light), texel_visibility(d, *frame, t), 1e-4);
      const float* tangent = d.maps.tangent.data + 3 * t;
      const model::Vec3d unit = normalize(model::Vec3d(tangent[0], tangent[1], tangent[2]));
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(x.tangent[c], (&unit.x)[c], 1e-6);
        EXPECT_EQ(x.colour[c], d.maps.albedo.data[3 * t + c]);
      }
      EXPECT_EQ(x.gap, std::clamp(d.maps.gap[t], 0.0f, 1.0f));
      EXPECT_EQ(x.yarn, d.maps.yarn_id[t]);
      EXPECT_EQ(x.cluster, count > 0 ? d.image_cluster[first] : h.label);
      if (::testing::Test::HasFailure()) return;  // one texel's report is enough
    }
    EXPECT_GE(records.stride(),
              sizeof(ControlVariateTexels::Header) + 4 * records.rank() + 2 * (widest - 1));
  }
}

// The destinations of the estimators' samples (bin_shift and shifted_destination, the plane of
// codes read directly) against the reader's depth of each bin, texel by texel, and the codes plane
// against bin_depth for every bin of a view.
namespace {
void expect_destinations_are_bin_depth_offsets(const std::string& path) {
  auto o = open(path);
  const EvalData& d = *evaluator_data(o->evaluator);
  SCOPED_TRACE(path);
  const double wo[3] = {-0.4, 0.1, 0.85};
  ShadingFrame frame;
  Status status;
  ASSERT_TRUE(make_frame(d, kReflectWi, wo, kAllLobes, &frame, &status));
  Rng rng(3);
  for (int k = 0; k < 4; ++k) {
    if (!(frame.parallax_bins.weight[k] > 0.0)) continue;
    const uint32_t bin = uint32_t(frame.parallax_bins.index[k]);
    const BinShift shift = bin_shift(d, frame, k);
    ASSERT_NE(shift.codes, nullptr);
    EXPECT_EQ(shift.codes, d.parallax.bin_codes(bin));
    for (uint32_t y = 0; y < d.n; ++y)
      for (uint32_t x = 0; x < d.n; ++x)
        ASSERT_EQ(-double(shift.codes[uint64_t(y) * d.n + x]) * shift.step,
                  d.parallax.bin_depth(bin, x, y));
    for (int s = 0; s < 2000; ++s) {
      // Points anywhere, also beyond the tile (it wraps).
      const double x = (rng.uniform() * 3.0 - 1.0) * d.n, y = (rng.uniform() * 3.0 - 1.0) * d.n;
      const double r = d.parallax.bin_depth(bin, int64_t(std::floor(x)), int64_t(std::floor(y)));
      int64_t tx = 0, ty = 0;
      bin_destination(d, frame, k, x, y, &tx, &ty);
      EXPECT_EQ(tx, int64_t(std::floor(x + r * frame.bin_offset_per_depth[k][0])));
      EXPECT_EQ(ty, int64_t(std::floor(y + r * frame.bin_offset_per_depth[k][1])));
    }
  }
}
}  // namespace

TEST(Multiscale, SampleDestinationsAreTheBinDepthOffsets) {
  for (const std::string* path : {&assets().twill, &assets().satin})  // raw and coded parallax
    expect_destinations_are_bin_depth_offsets(*path);
}

// The whole-tile push-forward sums of a view bin against an independent push-forward: s x s
// midpoint samples per source texel, each moved by its bin's Eq. 2 offset and counted in the
// texel it lands in. Each sample misplaces at most its own area, on one of the piece's two
// partition lines per axis, so the two differ by at most 2 N^2 max|channel| / s.
TEST(Multiscale, PushforwardSumsAreTheMovedTile) {
  auto o = open(assets().twill);
  const EvalData& d = *evaluator_data(o->evaluator);
  ASSERT_TRUE(d.basis.is_open());
  ASSERT_GT(d.visibility_rank(), 0u);
  const PushforwardChannels& layout = d.pushforward.layout();
  const double wo[3] = {-0.4, 0.1, 0.85};
  ShadingFrame frame;
  Status status;
  ASSERT_TRUE(make_frame(d, kReflectWi, wo, kAllLobes, &frame, &status));
  const uint32_t bin = uint32_t(frame.parallax_bins.index[0]);
  const double* sums = d.pushforward.bin_sums(bin);
  ASSERT_NE(sums, nullptr);
  const model::DirectionGrid<double> grid{int(d.parallax.dirs()), d.parallax.info().min_cos};
  const model::Vec3d c = grid.bin_center(int(bin) % grid.n, int(bin) / grid.n);
  const double fx = d.n * c.x / c.z, fy = d.n * c.y / c.z;
  const uint32_t s = 16;
  // Channels checked: the first image's mean part, the area of cluster 0 with every visibility
  // component, the gap of a cluster that has gaps.
  uint32_t gap_cluster = 0;
  for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t)
    if (d.maps.gap[t] < 0.5f) {
      gap_cluster = d.clusters.label_at(t);
      break;
    }
  std::vector<uint32_t> channels = {layout.spec(0, 0), layout.lobe(gap_cluster, 0) + 7};
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
    if (ch == layout.lobe(gap_cluster, 0) + 7)
      return d.clusters.label_at(t) == gap_cluster ? 1.0 - d.maps.gap[t] : 0.0;
    if (d.clusters.label_at(t) != 0) return 0.0;
    return e[(ch - layout.lobe(0, 0) - 6) / PushforwardChannels::kPerLobeGroup];
  };
  for (uint32_t ch : channels) {
    double sampled = 0, largest = 0;
    for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t)
      largest = std::max(largest, std::abs(channel(t, ch)));
    for (uint32_t qy = 0; qy < d.n; ++qy)
      for (uint32_t qx = 0; qx < d.n; ++qx) {
        const double r = d.parallax.bin_depth(bin, qx, qy);
        for (uint32_t b = 0; b < s; ++b)
          for (uint32_t a = 0; a < s; ++a) {
            const double x = qx + (a + 0.5) / s + r * fx, y = qy + (b + 0.5) / s + r * fy;
            sampled += channel(d.texel(int64_t(std::floor(x)), int64_t(std::floor(y))), ch) /
                       double(s * s);
          }
      }
    EXPECT_GT(largest, 0.0) << "channel " << ch;  // not 0 = 0
    EXPECT_LE(std::abs(sums[ch] - sampled), 2.0 * d.n * d.n * largest / s) << "channel " << ch;
  }
  // Mass: the area channels of all clusters add up to the tile.
  double area = 0;
  for (uint32_t k = 0; k < layout.clusters; ++k)
    area += sums[layout.lobe(k, 0) + 6];
  EXPECT_NEAR(area, double(d.n) * d.n, 1e-9 * d.n * d.n);
}

// Per-sample variance against brute force at equal samples (docs/evaluator.md, "The error
// budget"), on the 64^2 twill: the measured ratios, asserted with a floor below them.
TEST(Multiscale, HasFarLessVarianceThanBruteForceOnFarFieldFootprints) {
  auto o = open(assets().twill);
  const Footprint footprints[] = {{0, 0, 64, 64}, {-100, 7, 156, 263}, {-10.3, 5.7, 86.2, 133.9}};
  const double views[][3] = {{-0.1, 0.1, 0.99}, {-0.4, 0.1, 0.85}};
  for (const auto& wo : views)
    for (const Footprint& p : footprints) {
      const Stats ms = repeat(o->evaluator, p, kReflectWi, wo, Method::Multiscale, 2, 3000, 21);
      const Stats brute = repeat(o->evaluator, p, kReflectWi, wo, Method::Brute, 2, 3000, 21);
      const double ratio = (brute.sd_green * brute.sd_green) / (ms.sd_green * ms.sd_green);
      std::printf("variance ratio brute / multiscale at 2 spp, view (%g, %g, %g), %gx%g: %.1f\n",
                  wo[0], wo[1], wo[2], p.x1 - p.x0, p.y1 - p.y0, ratio);
      EXPECT_GT(ratio, kVarianceRatioFloor);
    }
}

TEST(MultiscalePaper, IsBiasedWhereTheFootprintMeanAlbedoDoesNotHold) {
  // The twill's warp is indigo and its weft undyed: kbar times the clustered D differs from the
  // sum of k D, so the printed Eq. 9 is off by far more than its noise.
  auto o = open(assets().twill);
  const Footprint p{0, 0, 64, 64};
  const Stats st =
      repeat(o->evaluator, p, kReflectWi, kReflectWo, Method::MultiscalePaper, 2, 2000, 4);
  const Rgb ref = reference(o->evaluator, p, kReflectWi, kReflectWo);
  EXPECT_GT(std::abs(st.mean.g - ref.g), 20 * st.se.g);
}

// ---------------------------------------------------------------------------------------------
// Bad input.

TEST(Errors, BadArgumentsAreInvalidArgument) {
  auto o = open(assets().twill);
  Rng rng(1);
  Estimate e;
  const Footprint good{0, 0, 4, 4};
  const double zero[3] = {0, 0, 0};
  const double nan[3] = {NAN, 0, 1};
  const double inf[3] = {INFINITY, 0, 1};
  auto code = [&](const Footprint& p, const double* wi, const double* wo, Method m, uint32_t spp,
                  LobeMask mask) {
    return o->evaluator.estimate(p, wi, wo, m, spp, rng, mask, &e).code();
  };
  const auto invalid = reader::ErrorCode::InvalidArgument;
  EXPECT_EQ(code(good, zero, kReflectWo, Method::Multiscale, 2, kAllLobes), invalid);
  EXPECT_EQ(code(good, kReflectWi, nan, Method::Multiscale, 2, kAllLobes), invalid);
  EXPECT_EQ(code(good, inf, kReflectWo, Method::Brute, 2, kAllLobes), invalid);
  EXPECT_EQ(code({4, 0, 0, 4}, kReflectWi, kReflectWo, Method::Reference, 1, kAllLobes), invalid);
  EXPECT_EQ(code({0, NAN, 4, 4}, kReflectWi, kReflectWo, Method::Brute, 1, kAllLobes), invalid);
  EXPECT_EQ(code(good, kReflectWi, kReflectWo, Method::Brute, 0, kAllLobes), invalid);
  EXPECT_EQ(code(good, kReflectWi, kReflectWo, Method::Multiscale, 0, kAllLobes), invalid);
  EXPECT_EQ(code(good, kReflectWi, kReflectWo, Method::Multiscale, 2, 0), invalid);
  EXPECT_EQ(code(good, kReflectWi, kReflectWo, Method::Multiscale, 2, 1u << 7), invalid);
  EXPECT_EQ(code(good, kReflectWi, kReflectWo, Method(9), 2, kAllLobes), invalid);
  EXPECT_EQ(
      o->evaluator.estimate(good, kReflectWi, kReflectWo, Method::Brute, 2, rng, kAllLobes, nullptr)
          .code(),
      invalid);
  Evaluator closed;
  EXPECT_EQ(
      closed.estimate(good, kReflectWi, kReflectWo, Method::Brute, 2, rng, kAllLobes, &e).code(),
      invalid);
}

TEST(Errors, MethodsNeedTheirTables) {
  auto o = open(assets().bare);
  ASSERT_TRUE(o->evaluator.is_open());
  EXPECT_STREQ(o->evaluator.table_source(), "none");
  Rng rng(1);
  Estimate e;
  const Footprint p{0, 0, 8, 8};
  const Status s =
      o->evaluator.estimate(p, kReflectWi, kReflectWo, Method::Multiscale, 2, rng, kAllLobes, &e);
  EXPECT_EQ(s.code(), reader::ErrorCode::NotFound);
  EXPECT_NE(std::string(s.message()).find("Integral-Radiance"), std::string::npos);
  // Brute force and the reference need none.
  EXPECT_TRUE(
      o->evaluator.estimate(p, kReflectWi, kReflectWo, Method::Brute, 2, rng, kAllLobes, &e).ok());
  EXPECT_TRUE(
      o->evaluator.estimate(p, kReflectWi, kReflectWo, Method::Reference, 1, rng, kAllLobes, &e)
          .ok());
  // Asking for a representation the asset does not have fails at open.
  reader::Asset flat;
  ASSERT_TRUE(flat.open_file(assets().flat.c_str()).ok());
  Evaluator ev;
  EvalOptions options;
  options.tables = TableChoice::Raw;  // the flat asset holds the compressed tables only
  EXPECT_EQ(ev.open(flat, options).code(), reader::ErrorCode::NotFound);
}

TEST(Errors, MethodNamesRoundTrip) {
  for (int m = 0; m < kMethodCount; ++m) {
    Method parsed;
    ASSERT_TRUE(parse_method(method_name(Method(m)), &parsed));
    EXPECT_EQ(parsed, Method(m));
  }
  Method parsed;
  EXPECT_FALSE(parse_method("multiscale-unbiased", &parsed));
  EXPECT_FALSE(parse_method(nullptr, &parsed));
}

}  // namespace
}  // namespace clothbake::eval

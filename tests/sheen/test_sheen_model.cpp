// The sheen lobe of the model (model/sheen.hpp) with its fitted table (model/sheen_table.hpp):
// normalisation, sampling, white furnace, robustness, table sanity, and R against an independent
// Monte Carlo simulation of the sheen layer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "model/sheen.hpp"
#include "sheen/ltc_fit.hpp"
#include "sheen/rng.hpp"
#include "sheen/sheen_layer.hpp"
#include "sheen_test_util.hpp"

namespace model = clothbake::model;
namespace table = clothbake::model::sheen_table;
using clothbake::sheen::Rng;
using clothbake::sheen_test::integrate_hemisphere_grazing;
using model::SheenLtc;
using model::Vec3d;

namespace {

Vec3d direction(double cos_theta, double phi) {
  return clothbake::sheen_test::direction_zphi(cos_theta, phi);
}

double node_cos(int i) {
  return double(i) / (table::kCosCount - 1);
}
double node_roughness(int j) {
  return double(j) / (table::kRoughnessCount - 1);
}

// --- the LTC lobe itself ------------------------------------------------------------------------

// D integrates to 1 over the hemisphere for any lobe: for lobes of the kind the table holds, and
// for every node of the table.
TEST(SheenLtc, DensityIntegratesToOne) {
  const Vec3d wo = direction(0.4, 1.1);
  for (auto [a, b] :
       {std::array<double, 2>{1.0, 0.0}, {0.5, -0.2}, {0.1, -0.17}, {0.02, 0.05}, {1.3, 0.3}}) {
    const SheenLtc<double> ltc{a, b, 1.0};
    const double integral = integrate_hemisphere_grazing(
        [&](const Vec3d& wi) { return model::sheen_ltc_density(ltc, wi, wo); }, 3000, 256);
    EXPECT_NEAR(integral, 1.0, 2e-3) << "a " << a << " b " << b;
  }
}

TEST(SheenLtc, TableLobesIntegrateToOne) {
  double worst = 0.0;
  for (int j = 0; j < table::kRoughnessCount; j += 5)
    for (int i = 0; i < table::kCosCount; i += 5) {
      const double mu = std::max(node_cos(i), 1e-3);
      const Vec3d wo = direction(mu, 0.0);
      const SheenLtc<double> ltc = model::sheen_ltc(mu, node_roughness(j));
      const double integral = integrate_hemisphere_grazing(
          [&](const Vec3d& wi) { return model::sheen_ltc_density(ltc, wi, wo); }, 1200, 96);
      worst = std::max(worst, std::abs(integral - 1.0));
    }
  EXPECT_LT(worst, 3e-3);
}

// sheen_sample draws from sheen_pdf: chi-square over the hemisphere, for rough and smooth sheen,
// grazing and steep wo, and wo at several azimuths (the frame rotation).
TEST(SheenLtc, SamplesFollowThePdf) {
  Rng rng(31, 0);
  for (auto [mu, phi, roughness] : {std::array<double, 3>{0.7, 0.0, 0.8},
                                    {0.3, 2.0, 0.5},
                                    {0.08, -1.0, 0.25},
                                    {0.999, 0.5, 0.6}}) {
    const Vec3d wo = direction(mu, phi);
    const auto result = clothbake::sheen_test::chi_square_hemisphere(
        [&, roughness = roughness] {
          return model::sheen_sample(wo, roughness, rng.uniform(), rng.uniform());
        },
        [&, roughness = roughness](const Vec3d& wi) { return model::sheen_pdf(wi, wo, roughness); },
        300000);
    EXPECT_TRUE(result.passed) << result.message << " (mu " << mu << ", roughness " << roughness
                               << ")";
  }
}

// The harness above must be able to reject: samples of one LTC lobe checked against the density of
// a lobe 5% wider (a), or with the skew b moved by 0.05, fail.
TEST(SheenLtc, ChiSquareRejectsAWrongDensity) {
  const Vec3d wo = direction(0.4, 0.7);
  const SheenLtc<double> drawn{0.5, -0.1, 1.0};
  for (const SheenLtc<double>& claimed :
       {SheenLtc<double>{0.525, -0.1, 1.0}, SheenLtc<double>{0.5, -0.05, 1.0}}) {
    Rng rng(34, 0);
    const auto result = clothbake::sheen_test::chi_square_hemisphere(
        [&] { return model::sheen_ltc_sample(drawn, wo, rng.uniform(), rng.uniform()); },
        [&](const Vec3d& wi) { return model::sheen_ltc_density(claimed, wi, wo); }, 300000);
    EXPECT_FALSE(result.passed) << result.message;
  }
  // And the same samples against their own density pass (the control).
  Rng rng(34, 0);
  const auto control = clothbake::sheen_test::chi_square_hemisphere(
      [&] { return model::sheen_ltc_sample(drawn, wo, rng.uniform(), rng.uniform()); },
      [&](const Vec3d& wi) { return model::sheen_ltc_density(drawn, wi, wo); }, 300000);
  EXPECT_TRUE(control.passed) << control.message;
}

// f cos / pdf = R exactly for every sample: the estimator of sheen_sample has zero variance.
TEST(SheenLtc, SampleWeightIsTheAlbedo) {
  Rng rng(32, 0);
  for (int k = 0; k < 2000; ++k) {
    const Vec3d wo = direction(0.02 + 0.98 * rng.uniform(), 6.283 * rng.uniform());
    const double roughness = rng.uniform();
    const Vec3d wi = model::sheen_sample(wo, roughness, rng.uniform(), rng.uniform());
    const double pdf = model::sheen_pdf(wi, wo, roughness);
    if (!(pdf > 0.0)) continue;  // wi on the horizon (probability zero)
    const double weight = model::sheen_eval(wi, wo, roughness) * wi.z / pdf;
    ASSERT_NEAR(weight, model::sheen_albedo(wo.z, roughness), 1e-9);
  }
}

// White furnace: integral f cos dwi = R <= 1 (quadrature independent of the sampler).
TEST(SheenLtc, WhiteFurnaceGivesTheAlbedo) {
  for (auto [mu, roughness] :
       {std::array<double, 2>{0.05, 0.3}, {0.3, 0.9}, {0.6, 0.5}, {1.0, 1.0}, {0.15, 0.1}}) {
    const Vec3d wo = direction(mu, 0.8);
    const double integral = integrate_hemisphere_grazing(
        [&, roughness = roughness](const Vec3d& wi) {
          return model::sheen_eval(wi, wo, roughness) * wi.z;
        },
        3000, 256);
    const double albedo = model::sheen_albedo(mu, roughness);
    EXPECT_NEAR(integral, albedo, 2e-3 * albedo + 1e-9) << "mu " << mu;
    EXPECT_LE(integral, 1.0);
  }
}

// Finite, non-negative values for grazing directions and roughness at and beyond its range.
template <class T>
void check_robust() {
  using V = model::Vec3<T>;
  const T nan = std::numeric_limits<T>::quiet_NaN();
  const T roughnesses[] = {T(0), T(1e-7), T(0.5), T(1), T(-1), T(3), nan};
  const T cosines[] = {T(1e-9), T(1e-4), T(0.3), T(1)};
  for (T r : roughnesses)
    for (T co : cosines)
      for (T ci : cosines) {
        const T so = std::sqrt(T(1) - co * co), si = std::sqrt(T(1) - ci * ci);
        const V wo{so, T(0), co};
        for (const V& wi : {V{si, T(0), ci}, V{-si, T(0), ci}, V{T(0), si, ci}}) {
          const T f = model::sheen_eval(wi, wo, r), p = model::sheen_pdf(wi, wo, r);
          ASSERT_TRUE(std::isfinite(f) && f >= T(0)) << f;
          ASSERT_TRUE(std::isfinite(p) && p >= T(0)) << p;
        }
        const T albedo = model::sheen_albedo(co, r);
        ASSERT_TRUE(albedo >= T(0) && albedo <= T(1));
        for (T u : {T(0), T(0.5), T(0.999999)}) {
          const V wi = model::sheen_sample(wo, r, u, T(0.25));
          ASSERT_TRUE(std::isfinite(wi.x) && std::isfinite(wi.y) && wi.z >= T(0));
          ASSERT_NEAR(model::length(wi), T(1), T(1e-5));
        }
      }
  // Below the horizon: no sheen.
  const V up{T(0), T(0), T(1)}, down{T(0.6), T(0), T(-0.8)};
  EXPECT_EQ(model::sheen_eval(down, up, T(0.5)), T(0));
  EXPECT_EQ(model::sheen_eval(up, down, T(0.5)), T(0));
  EXPECT_EQ(model::sheen_pdf(up, down, T(0.5)), T(0));
  EXPECT_EQ(model::length(model::sheen_sample(down, T(0.5), T(0.3), T(0.3))), T(0));
}

TEST(SheenLtc, FiniteAtGrazingAnglesAndRoughnessExtremes) {
  check_robust<double>();
  check_robust<float>();
}

TEST(SheenLtc, FloatAgreesWithDouble) {
  Rng rng(33, 0);
  for (int k = 0; k < 1000; ++k) {
    const Vec3d wo = direction(0.05 + 0.95 * rng.uniform(), 6.283 * rng.uniform());
    const Vec3d wi = direction(0.05 + 0.95 * rng.uniform(), 6.283 * rng.uniform());
    const double r = rng.uniform();
    const double fd = model::sheen_eval(wi, wo, r);
    const float ff = model::sheen_eval(model::Vec3f(wi), model::Vec3f(wo), float(r));
    ASSERT_NEAR(ff, fd, 1e-4 * std::max(1.0, fd));
  }
}

// At the pole the lobe is the same for every azimuth of wo (b = 0 there), so eval is continuous.
TEST(SheenLtc, ContinuousThroughThePole) {
  const Vec3d wi = direction(0.3, 0.4);
  const double at_pole = model::sheen_eval(wi, Vec3d{0, 0, 1}, 0.5);
  for (double phi : {0.0, 1.0, 2.5, 4.0}) {
    const Vec3d wo = direction(1.0 - 1e-9, phi);
    EXPECT_NEAR(model::sheen_eval(wi, wo, 0.5), at_pole, 1e-3 * at_pole);
  }
}

// --- the fitted table ---------------------------------------------------------------------------

TEST(SheenTable, NodesAreFiniteAndInRange) {
  for (int j = 0; j < table::kRoughnessCount; ++j)
    for (int i = 0; i < table::kCosCount; ++i) {
      const float* node = table::kTable[j][i];
      EXPECT_TRUE(std::isfinite(node[0]) && node[0] > 0.0f) << i << "," << j;
      EXPECT_TRUE(std::isfinite(node[1])) << i << "," << j;
      EXPECT_TRUE(node[2] >= 0.0f && node[2] <= 1.0f) << i << "," << j;
    }
}

// The lobe of a wo along the normal must be rotationally symmetric: b = 0 on the pole row.
TEST(SheenTable, PoleRowIsSymmetric) {
  for (int j = 0; j < table::kRoughnessCount; ++j)
    EXPECT_EQ(table::kTable[j][table::kCosCount - 1][1], 0.0f) << j;
}

// Roughness 0 reflects nothing: R = 0 exactly on that row (sheen/sheen_layer.cpp).
TEST(SheenTable, RoughnessZeroRowHasZeroAlbedo) {
  for (int i = 0; i < table::kCosCount; ++i)
    EXPECT_EQ(table::kTable[0][i][2], 0.0f) << i;
}

// R grows towards grazing incidence (a longer path through the fibres' top layer), at every
// roughness: R(cos_i) >= R(cos_i+1) up to the Monte Carlo noise of the two nodes.
TEST(SheenTable, AlbedoDecreasesWithCosTheta) {
  const double n = double(table::kPathsPerNode);
  for (int j = 1; j < table::kRoughnessCount; ++j)
    for (int i = 0; i + 1 < table::kCosCount; ++i) {
      const double r0 = table::kTable[j][i][2], r1 = table::kTable[j][i + 1][2];
      const double se = std::sqrt((r0 * (1 - r0) + r1 * (1 - r1)) / n);
      EXPECT_GE(r0, r1 - 4.0 * se - 1e-7) << "cos node " << i << ", roughness node " << j;
    }
}

// Sheen exists at grazing incidence for any roughness above 0.
TEST(SheenTable, GrazingAlbedoIsSubstantial) {
  for (int j = 1; j < table::kRoughnessCount; ++j)
    EXPECT_GT(table::kTable[j][0][2], 0.3f) << j;
}

// Bilinear interpolation error bound at (cos, roughness) from the table's second differences
// around the cell: h^2 / 8 max |f''| per axis (MC noise in the differences only loosens it).
double interpolation_bound(double cos_theta, double roughness) {
  const int i = std::min(int(cos_theta * (table::kCosCount - 1)), table::kCosCount - 2);
  const int j = std::min(int(roughness * (table::kRoughnessCount - 1)), table::kRoughnessCount - 2);
  auto R = [](int ii, int jj) {
    ii = std::clamp(ii, 0, table::kCosCount - 1);
    jj = std::clamp(jj, 0, table::kRoughnessCount - 1);
    return double(table::kTable[jj][ii][2]);
  };
  double d_cos = 0.0, d_rough = 0.0;
  for (int jj = j; jj <= j + 1; ++jj)
    for (int ii = std::max(i, 1); ii <= std::min(i + 1, table::kCosCount - 2); ++ii)
      d_cos = std::max(d_cos, std::abs(R(ii - 1, jj) - 2 * R(ii, jj) + R(ii + 1, jj)));
  for (int ii = i; ii <= i + 1; ++ii)
    for (int jj = std::max(j, 1); jj <= std::min(j + 1, table::kRoughnessCount - 2); ++jj)
      d_rough = std::max(d_rough, std::abs(R(ii, jj - 1) - 2 * R(ii, jj) + R(ii, jj + 1)));
  // The second difference is h^2 f''; the bilinear error is at most h^2 / 8 |f''| per axis.
  return (d_cos + d_rough) / 8.0;
}

// R between nodes against a new simulation of the layer (another seed, so independent of the
// table's run): |R_table - R_mc| <= 4 sigma of the two Monte Carlo errors + interpolation bound.
TEST(SheenTable, AlbedoMatchesAnIndependentSimulation) {
  for (auto [mu, roughness] : {std::array<double, 2>{0.37, 0.61},
                               {0.12, 0.33},
                               {0.83, 0.9},
                               {0.05, 0.15},
                               {0.55, 0.45},
                               {0.2, 0.97}}) {
    clothbake::sheen::LayerSimulationSettings s;
    s.paths = 150000;
    s.seed = table::kSeed + 1000;
    s.histogram = false;
    const auto sim = clothbake::sheen::simulate_sheen_layer(mu, roughness, s);
    const double table_r = model::sheen_albedo(mu, roughness);
    const double table_se =
        std::sqrt(std::max(table_r * (1 - table_r), 0.0) / double(table::kPathsPerNode));
    const double tolerance = 4.0 * std::hypot(sim.albedo_standard_error(), table_se) +
                             interpolation_bound(mu, roughness);
    EXPECT_NEAR(table_r, sim.albedo(), tolerance) << "cos " << mu << ", roughness " << roughness;
  }
}

// The lobe shape between nodes: the table's LTC is much closer to the simulated distribution of
// exit directions than the plain cosine lobe is (L1 distance over the simulation's bins).
TEST(SheenTable, LobeShapeFollowsTheSimulation) {
  using namespace clothbake::sheen;
  const LtcBinQuadrature quadrature(ExitBinning{32, 32});
  for (auto [mu, roughness] :
       {std::array<double, 2>{0.1, 0.5}, {0.4, 0.8}, {0.25, 0.3}, {0.7, 0.65}}) {
    LayerSimulationSettings s;
    s.paths = 200000;
    s.seed = table::kSeed + 2000;
    const LayerSimulation sim = simulate_sheen_layer(mu, roughness, s);
    std::vector<double> target(sim.exit_counts.size()), ltc, cosine;
    for (std::size_t k = 0; k < target.size(); ++k)
      target[k] = double(sim.exit_counts[k]) / double(sim.reflected);
    const SheenLtc<double> lobe = model::sheen_ltc(mu, roughness);
    quadrature.bin_probabilities(lobe.a, lobe.b, ltc);
    quadrature.bin_probabilities(1.0, 0.0, cosine);
    double l1_ltc = 0.0, l1_cosine = 0.0;
    for (std::size_t k = 0; k < target.size(); ++k) {
      l1_ltc += std::abs(target[k] - ltc[k]);
      l1_cosine += std::abs(target[k] - cosine[k]);
    }
    EXPECT_LT(l1_ltc, 0.5 * l1_cosine) << "cos " << mu << ", roughness " << roughness;
    EXPECT_LT(l1_ltc, 0.4) << "cos " << mu << ", roughness " << roughness;
  }
}

}  // namespace

// The Monte Carlo simulation of the sheen layer (sheen/sheen_layer.hpp) against analytic
// single-scattering results, the exact R = 0 at roughness 0, and its bookkeeping.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <stdexcept>

#include "model/spongecake.hpp"
#include "sheen/sheen_layer.hpp"
#include "sheen_test_util.hpp"

using namespace clothbake::sheen;

namespace {

// Roughness 1 is a conservative isotropic-scattering slab of optical thickness 1. Its
// single-scattering albedo for incidence mu0 is, integrating the first-collision depth t and the
// exit cosine mu (Chandrasekhar 1960, first-order term):
//   A1(mu0) = 1/2 int_0^1 mu / (mu + mu0) (1 - exp(-(1/mu0 + 1/mu))) dmu.
double isotropic_single_scattering_albedo(double mu0) {
  const int n = 200000;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const double mu = (k + 0.5) / n;
    sum += mu / (mu + mu0) * (1.0 - std::exp(-(1.0 / mu0 + 1.0 / mu)));
  }
  return 0.5 * sum / n;
}

TEST(SheenLayer, SingleScatteringOfTheIsotropicSlabMatchesTheClosedForm) {
  for (double mu0 : {0.05, 0.5, 1.0}) {
    LayerSimulationSettings s;
    s.paths = 400000;
    s.seed = 11;
    s.max_order = 1;
    const LayerSimulation sim = simulate_sheen_layer(mu0, 1.0, s);
    const double expected = isotropic_single_scattering_albedo(mu0);
    EXPECT_NEAR(sim.albedo(), expected, 4.5 * sim.albedo_standard_error() + 1e-6) << "mu0 " << mu0;
  }
}

// Single scattering for an anisotropic layer (roughness 0.6): by quadrature of the first-collision
// depth in closed form and the exit direction numerically, with the directional extinction
// sigma_t(w) = sigma(w) of the SGGX flakes:
//   A1 = int_{z>0} p(wo -> w) s0 / (s0 + s1) (1 - exp(-(s0 + s1))) dw,
//   s0 = sigma(wo) / mu0, s1 = sigma(w) / w.z  (optical depth per unit thickness).
TEST(SheenLayer, SingleScatteringOfAFibreLayerMatchesQuadrature) {
  const double roughness = 0.6;
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(roughness);
  for (double mu0 : {0.1, 0.6}) {
    const Vec3d wo{std::sqrt(1 - mu0 * mu0), 0.0, mu0};
    const double s0 = flakes.projected_area(wo) / mu0;
    const double expected = clothbake::sheen_test::integrate_hemisphere(
        [&](const Vec3d& w) {
          const double s1 = flakes.projected_area(w) / w.z;
          return flakes.phase(wo, w) * s0 / (s0 + s1) * (1.0 - std::exp(-(s0 + s1)));
        },
        1500, 512);
    LayerSimulationSettings s;
    s.paths = 400000;
    s.seed = 12;
    s.max_order = 1;
    const LayerSimulation sim = simulate_sheen_layer(mu0, roughness, s);
    EXPECT_NEAR(sim.albedo(), expected, 4.5 * sim.albedo_standard_error() + 2e-4) << "mu0 " << mu0;
  }
}

// The model's closed-form SpongeCake lobes (model/spongecake.hpp) against this independent random
// walk truncated at one scattering: the layer is a SpongeCake slab of optical thickness T = 1,
// tangent +z, SGGX roughness sigma = r^2 and albedo 1. Single-scattered light leaves through the
// top with probability int f_r |i_z| di and through the bottom with probability int f_t |i_z| di
// (the bottom count also holds the unscattered e^{-T Lambda(o)}). This checks f_r and f_t, their
// factor 4, Lambda and the half vector h = normalize(i + o) used for transmission, against
// transport that shares no formula with them (a flipped-o half vector moves the transmitted
// fraction by far more than the tolerance).
TEST(SheenLayer, SpongeCakeLobesMatchSimulatedSingleScattering) {
  for (auto [mu0, roughness] : {std::array<double, 2>{0.25, 0.8}, {0.7, 0.6}}) {
    const double sigma = roughness * roughness;
    const auto slab = clothbake::model::FibreSggx<double>::make({0, 0, 1}, sigma);
    const Vec3d wo{std::sqrt(1 - mu0 * mu0), 0.0, mu0};
    const double reflected = clothbake::sheen_test::integrate_zphi(
        [&](const Vec3d& wi) {
          return clothbake::model::spongecake_reflection(slab, 1.0, wi, wo) * std::abs(wi.z);
        },
        0.0, 1.0, 1000, 256);
    const double transmitted = clothbake::sheen_test::integrate_zphi(
        [&](const Vec3d& wi) {
          return clothbake::model::spongecake_transmission(slab, 1.0, wi, wo) * std::abs(wi.z);
        },
        -1.0, 0.0, 1000, 256);
    const double unscattered =
        clothbake::model::spongecake_unscattered_transmittance(slab, 1.0, wo);
    LayerSimulationSettings s;
    s.paths = 400000;
    s.seed = 13;
    s.max_order = 1;
    s.histogram = false;
    const LayerSimulation sim = simulate_sheen_layer(mu0, roughness, s);
    const double n = double(sim.paths);
    const double sim_t = double(sim.transmitted) / n;
    const double se_t = std::sqrt(sim_t * (1 - sim_t) / n);
    EXPECT_NEAR(sim.albedo(), reflected, 4.5 * sim.albedo_standard_error() + 2e-4)
        << "mu0 " << mu0 << " roughness " << roughness;
    EXPECT_NEAR(sim_t, transmitted + unscattered, 4.5 * se_t + 2e-4)
        << "mu0 " << mu0 << " roughness " << roughness;
  }
}

// Roughness 0 reflects nothing (flake normals are horizontal), at every angle.
TEST(SheenLayer, RoughnessZeroReflectsNothing) {
  for (double mu0 : {0.001, 0.3, 1.0}) {
    LayerSimulationSettings s;
    s.paths = 1000;
    const LayerSimulation sim = simulate_sheen_layer(mu0, 0.0, s);
    EXPECT_EQ(sim.reflected, 0u);
    EXPECT_EQ(sim.transmitted, s.paths);
    EXPECT_EQ(sim.albedo(), 0.0);
  }
}

TEST(SheenLayer, EveryPathIsAccountedForAndTheHistogramHoldsTheReflectedOnes) {
  LayerSimulationSettings s;
  s.paths = 20000;
  const LayerSimulation sim = simulate_sheen_layer(0.3, 0.5, s);
  EXPECT_EQ(sim.reflected + sim.transmitted + sim.truncated, sim.paths);
  EXPECT_EQ(sim.truncated, 0u);
  uint64_t histogram = 0;
  for (uint64_t c : sim.exit_counts)
    histogram += c;
  EXPECT_EQ(histogram, sim.reflected);
  EXPECT_GT(sim.reflected, 0u);
  EXPECT_GT(sim.transmitted, 0u);
}

TEST(SheenLayer, DeterministicPerSeedAndStream) {
  LayerSimulationSettings s;
  s.paths = 5000;
  const LayerSimulation a = simulate_sheen_layer(0.2, 0.4, s);
  const LayerSimulation b = simulate_sheen_layer(0.2, 0.4, s);
  EXPECT_EQ(a.reflected, b.reflected);
  EXPECT_EQ(a.exit_counts, b.exit_counts);
  s.stream = 1;
  const LayerSimulation c = simulate_sheen_layer(0.2, 0.4, s);
  EXPECT_NE(a.exit_counts, c.exit_counts);
}

TEST(SheenLayer, ExitBinsHaveTheDocumentedEdges) {
  ExitBinning binning{4, 8};
  EXPECT_EQ(binning.bin_of(clothbake::sheen_test::direction_zphi(0.999, 0.01)), 3 * 8 + 0);
  // z = 0.2 lies in [(1/4)^2, (2/4)^2) = [0.0625, 0.25): z bin 1; phi = -2.0 folds to 2.0.
  EXPECT_EQ(binning.bin_of(clothbake::sheen_test::direction_zphi(0.2, -2.0)),
            1 * 8 + int(2.0 / kPi * 8));
  EXPECT_EQ(binning.bin_of(clothbake::sheen_test::direction_zphi(0.0, 3.14159)), 0 * 8 + 7);
}

TEST(SheenLayer, RejectsArgumentsOutsideTheirRange) {
  LayerSimulationSettings s;
  s.paths = 10;
  EXPECT_THROW(simulate_sheen_layer(0.0, 0.5, s), std::invalid_argument);
  EXPECT_THROW(simulate_sheen_layer(1.5, 0.5, s), std::invalid_argument);
  EXPECT_THROW(simulate_sheen_layer(0.5, -0.1, s), std::invalid_argument);
  EXPECT_THROW(simulate_sheen_layer(0.5, NAN, s), std::invalid_argument);
}

// A path cut by the published rules counts as reflected iff its last direction points up, so
// every path ends up reflected or transmitted; with a cap of one event the reflected fraction is
// that of paths whose first scattering sends them up (more than the paths that also escape).
TEST(SheenLayer, PublishedRulesClassifyCutPathsByTheirLastDirection) {
  LayerSimulationSettings s;
  s.paths = 20000;
  s.max_order = 1;
  s.classify_by_last_direction = true;
  const LayerSimulation cut = simulate_sheen_layer(0.3, 0.5, s);
  EXPECT_EQ(cut.reflected + cut.transmitted, cut.paths);
  EXPECT_GT(cut.truncated, 0u);
  s.classify_by_last_direction = false;
  const LayerSimulation kept = simulate_sheen_layer(0.3, 0.5, s);
  EXPECT_EQ(kept.reflected + kept.transmitted + kept.truncated, kept.paths);
  EXPECT_GT(cut.albedo(), kept.albedo() + 0.05);
  uint64_t histogram = 0;
  for (uint64_t c : cut.exit_counts)
    histogram += c;
  EXPECT_EQ(histogram, cut.reflected);
}

}  // namespace

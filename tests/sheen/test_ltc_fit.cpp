// The LTC lobe fit (sheen/ltc_fit.hpp): its quadrature is a probability distribution, and it
// recovers known lobes from exact bin probabilities and from sampled histograms.
#include <gtest/gtest.h>

#include <cmath>

#include "model/sheen.hpp"
#include "sheen/ltc_fit.hpp"
#include "sheen/rng.hpp"

using namespace clothbake::sheen;
using clothbake::model::SheenLtc;

namespace {

TEST(LtcFit, BinSolidAnglesCoverTheHemisphereAndProbabilitiesSumToOne) {
  const LtcBinQuadrature quadrature(ExitBinning{32, 32});
  double total = 0.0;
  for (double omega : quadrature.bin_solid_angles())
    total += omega;
  EXPECT_NEAR(total, 2.0 * kPi, 1e-12);
  std::vector<double> p;
  for (auto [a, b] : {std::array<double, 2>{1.0, 0.0}, {0.3, -0.15}, {0.6, 0.1}}) {
    quadrature.bin_probabilities(a, b, p);
    double sum = 0.0;
    for (double v : p) {
      EXPECT_GE(v, 0.0);
      sum += v;
    }
    EXPECT_NEAR(sum, 1.0, 2e-4) << "a " << a << " b " << b;
  }
}

// The quadrature's density is the model's (model::sheen_ltc_density, what a renderer evaluates):
// bin probabilities against an independent fine midpoint integration of the model function, for
// a wo at any elevation in the xz plane.
TEST(LtcFit, BinProbabilitiesIntegrateTheModelDensity) {
  const ExitBinning binning{8, 8};
  const LtcBinQuadrature quadrature(binning, 4);
  const double a = 0.3, b = -0.12;
  std::vector<double> p;
  quadrature.bin_probabilities(a, b, p);
  const SheenLtc<double> ltc{a, b, 1.0};
  for (double mu : {0.2, 0.9}) {
    const Vec3d wo{std::sqrt(1 - mu * mu), 0.0, mu};
    for (int bin : {0, 9, 27, 40, 63}) {
      const int iz = bin / binning.phi_bins, ip = bin % binning.phi_bins;
      const double z0 = binning.z_edge(iz), z1 = binning.z_edge(iz + 1);
      const double p0 = kPi * ip / binning.phi_bins, p1 = kPi * (ip + 1) / binning.phi_bins;
      const int n = 400;
      double sum = 0.0;
      for (int u = 0; u < n; ++u)
        for (int v = 0; v < n; ++v) {
          const double z = z0 + (z1 - z0) * (u + 0.5) / n, phi = p0 + (p1 - p0) * (v + 0.5) / n;
          const double s = std::sqrt(1 - z * z);
          // Both halves of the folded bin: +phi and -phi.
          sum += clothbake::model::sheen_ltc_density(
                     ltc, Vec3d{s * std::cos(phi), s * std::sin(phi), z}, wo) +
                 clothbake::model::sheen_ltc_density(
                     ltc, Vec3d{s * std::cos(phi), -s * std::sin(phi), z}, wo);
        }
      const double expected = sum * (z1 - z0) * (p1 - p0) / (n * n);
      EXPECT_NEAR(p[std::size_t(bin)], expected, 1e-4 * expected + 1e-9) << "bin " << bin;
    }
  }
}

// Exact bin probabilities of a known lobe (finer quadrature than the fit's) are fitted back.
TEST(LtcFit, RecoversAKnownLobeFromExactBinProbabilities) {
  const ExitBinning binning{32, 32};
  const LtcBinQuadrature fine(binning, 4), quadrature(binning, 3);
  for (auto [a, b] : {std::array<double, 2>{0.35, -0.12}, {0.08, -0.17}, {0.7, 0.05}}) {
    std::vector<double> target;
    fine.bin_probabilities(a, b, target);
    const LtcFit fit = fit_ltc_lobe(target, quadrature, {{1.0, 0.0}}, false);
    EXPECT_NEAR(fit.a, a, 2e-3 * a) << "a " << a << " b " << b;
    EXPECT_NEAR(fit.b, b, 2e-3) << "a " << a << " b " << b;
    EXPECT_LT(fit.l1_error, 2e-3);
  }
}

// A histogram of directions drawn with model::sheen_ltc_sample from a known lobe: the fit finds the
// lobe within the sampling noise, and its L1 error is close to the predicted noise floor.
TEST(LtcFit, RecoversAKnownLobeFromSampledDirections) {
  const ExitBinning binning{32, 32};
  const LtcBinQuadrature quadrature(binning);
  const double mu = 0.4, a = 0.4, b = -0.1;
  const Vec3d wo{std::sqrt(1 - mu * mu), 0.0, mu};
  const SheenLtc<double> ltc{a, b, 1.0};
  Rng rng(21, 0);
  const int n = 400000;
  std::vector<double> target(std::size_t(binning.bin_count()), 0.0);
  for (int k = 0; k < n; ++k) {
    const Vec3d w = clothbake::model::sheen_ltc_sample(ltc, wo, rng.uniform(), rng.uniform());
    target[std::size_t(binning.bin_of(w))] += 1.0 / n;
  }
  const LtcFit fit = fit_ltc_lobe(target, quadrature, {{1.0, 0.0}}, false);
  EXPECT_NEAR(fit.a, a, 0.01);
  EXPECT_NEAR(fit.b, b, 0.01);
  const double noise = expected_noise_l1(target, n);
  EXPECT_LT(fit.l1_error, 1.15 * noise);
  EXPECT_GT(fit.l1_error, 0.85 * noise);
}

TEST(LtcFit, PoleFitKeepsBZero) {
  const ExitBinning binning{16, 16};
  const LtcBinQuadrature quadrature(binning);
  std::vector<double> target;
  quadrature.bin_probabilities(0.5, 0.0, target);
  const LtcFit fit = fit_ltc_lobe(target, quadrature, {{1.0, 0.0}}, true);
  EXPECT_EQ(fit.b, 0.0);
  EXPECT_NEAR(fit.a, 0.5, 1e-4);
}

}  // namespace

// Self-tests of the statistical harness (tests/model/chi2.hpp): the incomplete gamma function
// against closed forms, the quadrature against known integrals, a correct sampler passing, and
// deliberately wrong densities failing.
#include <gtest/gtest.h>

#include <cmath>

#include "model/diffuse.hpp"
#include "tests/model/chi2.hpp"

namespace {

namespace m = clothbake::model;
namespace test = clothbake::test;
using m::Vec3d;

TEST(Chi2Harness, IncompleteGammaClosedForms) {
  for (double x : {0.0, 0.1, 1.0, 3.0, 10.0, 40.0}) {
    EXPECT_NEAR(test::regularized_gamma_q(1.0, x), std::exp(-x), 1e-14);  // Q(1, x) = e^-x
    EXPECT_NEAR(test::regularized_gamma_q(0.5, x), std::erfc(std::sqrt(x)), 1e-13);
    EXPECT_NEAR(test::regularized_gamma_q(2.0, x), (1 + x) * std::exp(-x), 1e-14);
    EXPECT_NEAR(test::chi2_p_value(x, 2), std::exp(-x / 2), 1e-14);
  }
  // Large dof: the chi-square median is about k (1 - 2/(9k))^3 (Wilson-Hilferty).
  const int k = 2000;
  EXPECT_NEAR(test::chi2_p_value(k * std::pow(1 - 2.0 / (9 * k), 3), k), 0.5, 2e-3);
  EXPECT_NEAR(test::sidak_level(0.01, 1), 0.01, 1e-15);
  EXPECT_NEAR(test::sidak_level(0.01, 10), 1 - std::pow(0.99, 0.1), 1e-15);
}

TEST(Chi2Harness, QuadratureIntegratesKnownFunctions) {
  EXPECT_NEAR(test::adaptive_simpson([](double x) { return std::sin(x); }, 0.0, M_PI, 1e-12), 2.0,
              1e-11);
  EXPECT_NEAR(test::composite_adaptive_simpson([](double x) { return std::exp(-x * x * 1e4); },
                                               -1.0, 1.0, 64, 1e-12),
              std::sqrt(M_PI) / 100, 1e-11);
  const test::SphereFrame frame = test::SphereFrame::around(m::normalize(Vec3d{1, 2, 3}));
  EXPECT_NEAR(test::integrate_sphere([](const Vec3d&) { return 1.0; }, frame, 4, 8, 1e-12),
              4 * M_PI, 1e-10);
  EXPECT_NEAR(
      test::integrate_sphere([](const Vec3d& w) { return std::abs(w.z); }, frame, 8, 16, 1e-12),
      2 * M_PI, 1e-8);
  EXPECT_NEAR(test::integrate_sphere([](const Vec3d& w) { return w.x * w.x; }, frame, 4, 8, 1e-12),
              4 * M_PI / 3, 1e-9);
}

Vec3d uniform_sphere(double u1, double u2) {
  const double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * M_PI * u2;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

TEST(Chi2Harness, CorrectSamplerPasses) {
  test::Chi2Options opt;
  opt.seed = 3;
  auto sampler = [](double, double u1, double u2, Vec3d& out) {
    out = m::sample_cosine_hemisphere(u1, u2);
    return true;
  };
  auto pdf = [](const Vec3d& w) { return w.z > 0 ? w.z / M_PI : 0.0; };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_mass, 1.0, 1e-6);
}

// Cosine-weighted samples checked against a uniform hemisphere density must fail.
TEST(Chi2Harness, WrongDensityFails) {
  test::Chi2Options opt;
  opt.seed = 4;
  auto sampler = [](double, double u1, double u2, Vec3d& out) {
    out = m::sample_cosine_hemisphere(u1, u2);
    return true;
  };
  auto pdf = [](const Vec3d& w) { return w.z > 0 ? 1 / (2 * M_PI) : 0.0; };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_FALSE(r.passed) << r.message;
  // A subtler error: a density 3% too peaked (z^1.03 renormalised).
  auto pdf2 = [](const Vec3d& w) {
    return w.z > 0 ? std::pow(w.z, 1.03) * 2.03 / (2 * M_PI) : 0.0;
  };
  auto r2 = test::chi2_test(sampler, pdf2, opt);
  EXPECT_FALSE(r2.passed) << r2.message;
}

// Samples where the density is zero are a hard failure.
TEST(Chi2Harness, SamplesOutsideTheSupportFail) {
  test::Chi2Options opt;
  auto sampler = [](double, double u1, double u2, Vec3d& out) {
    out = uniform_sphere(u1, u2);
    return true;
  };
  auto pdf = [](const Vec3d& w) { return w.z > 0 ? 1 / (2 * M_PI) : 0.0; };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_FALSE(r.passed);
  EXPECT_GT(r.outside, 0);
}

// A sampler that fails 30% of the time matches a density of mass 0.7 (the failure bucket), and a
// density claiming mass 0.8 fails.
TEST(Chi2Harness, MissingMassIsCounted) {
  test::Chi2Options opt;
  opt.seed = 6;
  auto sampler = [](double u0, double u1, double u2, Vec3d& out) {
    if (u0 < 0.3) return false;
    out = uniform_sphere(u1, u2);
    return true;
  };
  auto r = test::chi2_test(
      sampler, [](const Vec3d&) { return 0.7 / (4 * M_PI); }, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(double(r.failures) / opt.samples, 0.3, 3e-3);
  auto wrong = test::chi2_test(
      sampler, [](const Vec3d&) { return 0.8 / (4 * M_PI); }, opt);
  EXPECT_FALSE(wrong.passed) << wrong.message;
}

}  // namespace

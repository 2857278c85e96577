// SpongeCake specular lobes (model/spongecake.hpp): the formulas against a direct long-double
// transcription, closed forms for isotropic flakes (S = I), the Lambda_i -> Lambda_o limit, T -> 0
// and T -> inf, grazing directions, reciprocity, energy, and chi-square tests of the sampler.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "model/sggx.hpp"
#include "model/spongecake.hpp"
#include "tests/model/chi2.hpp"

namespace {

using clothbake::model::FibreSggx;
using clothbake::model::Vec3d;
using clothbake::model::Vec3f;
namespace m = clothbake::model;
namespace test = clothbake::test;
using LD = long double;

const double kInf = std::numeric_limits<double>::infinity();

Vec3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    Vec3d v{g(rng), g(rng), g(rng)};
    double l = m::length(v);
    if (l > 1e-6) return v / l;
  }
}

// The brief's formulas transcribed literally in long double (valid away from the stiff limits).
LD naive_reflection(const FibreSggx<double>& d, double T, const Vec3d& i, const Vec3d& o) {
  LD li = LD(d.projected_area(i)) / std::abs(LD(i.z)),
     lo = LD(d.projected_area(o)) / std::abs(LD(o.z));
  return LD(d.D(i + o)) * (1 - std::exp(-LD(T) * (li + lo))) /
         (4 * std::abs(LD(i.z)) * std::abs(LD(o.z)) * (li + lo));
}
LD naive_transmission(const FibreSggx<double>& d, double T, const Vec3d& i, const Vec3d& o) {
  LD li = LD(d.projected_area(i)) / std::abs(LD(i.z)),
     lo = LD(d.projected_area(o)) / std::abs(LD(o.z));
  return LD(d.D(i + o)) * (std::exp(-LD(T) * lo) - std::exp(-LD(T) * li)) /
         (4 * std::abs(LD(i.z)) * std::abs(LD(o.z)) * (li - lo));
}

TEST(SpongeCake, MatchesTheFormulas) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  int checked_r = 0, checked_t = 0;
  for (int k = 0; k < 20000; ++k) {
    const double sigma = 0.02 + 0.98 * uni(rng), T = 0.05 + 5 * uni(rng);
    auto d = FibreSggx<double>::make(random_unit(rng), sigma);
    Vec3d i = random_unit(rng), o = random_unit(rng);
    if (std::abs(i.z) < 0.05 || std::abs(o.z) < 0.05) continue;
    if (i.z * o.z > 0) {
      const double f = m::spongecake_reflection(d, T, i, o);
      ASSERT_NEAR(f, double(naive_reflection(d, T, i, o)), 1e-12 * f + 1e-300);
      ASSERT_EQ(m::spongecake_transmission(d, T, i, o), 0.0);
      ++checked_r;
    } else {
      const LD li = d.projected_area(i) / std::abs(i.z), lo = d.projected_area(o) / std::abs(o.z);
      if (std::abs(li - lo) < 1e-3) continue;  // the naive form cancels there (tested below)
      const double f = m::spongecake_transmission(d, T, i, o);
      ASSERT_NEAR(f, double(naive_transmission(d, T, i, o)), 1e-11 * f + 1e-300);
      ASSERT_EQ(m::spongecake_reflection(d, T, i, o), 0.0);
      ++checked_t;
    }
  }
  EXPECT_GT(checked_r, 5000);
  EXPECT_GT(checked_t, 5000);
}

// Isotropic flakes (sigma = 1): D = 1/pi, sigma(w) = 1, so f_r = (1 - e^{-T(1/mu_i + 1/mu_o)}) /
// (4 pi (mu_i + mu_o)) and f_t = (e^{-T/mu_o} - e^{-T/mu_i}) / (4 pi (mu_o - mu_i)).
TEST(SpongeCake, IsotropicClosedForms) {
  auto d = FibreSggx<double>::make({0.3, 0.4, 0.5}, 1.0);
  std::mt19937_64 rng(2);
  for (int k = 0; k < 5000; ++k) {
    Vec3d i = random_unit(rng), o = random_unit(rng);
    const double mi = std::abs(i.z), mo = std::abs(o.z), T = 0.7;
    if (mi < 1e-3 || mo < 1e-3) continue;
    if (i.z * o.z > 0) {
      const double ref = -std::expm1(-T * (1 / mi + 1 / mo)) / (4 * M_PI * (mi + mo));
      ASSERT_NEAR(m::spongecake_reflection(d, T, i, o), ref, 1e-13 * ref);
      ASSERT_NEAR(m::spongecake_reflection(d, kInf, i, o), 1 / (4 * M_PI * (mi + mo)), 1e-13);
    } else if (std::abs(mi - mo) > 1e-6) {
      const double ref = (std::exp(-T / mo) - std::exp(-T / mi)) / (4 * M_PI * (mo - mi));
      ASSERT_NEAR(m::spongecake_transmission(d, T, i, o), ref, 1e-9 * ref);
    }
  }
}

// Hemispherical albedo for light leaving towards o: integral of f |i_z| over i, by quadrature.
double albedo(const FibreSggx<double>& d, double T, const Vec3d& o, bool reflection, int z_bins = 8,
              int phi_bins = 16) {
  auto f = [&](const Vec3d& i) {
    return (reflection ? m::spongecake_reflection(d, T, i, o)
                       : m::spongecake_transmission(d, T, i, o)) *
           std::abs(i.z);
  };
  return test::integrate_sphere(f, test::SphereFrame{}, z_bins, phi_bins, 1e-10, 14);
}

// Semi-infinite isotropic slab: the single-scattering albedo is (1/2)(1 - mu ln(1 + 1/mu))
// (Chandrasekhar's isotropic single scattering, since the specular sphere's phase function is
// isotropic); finite T against a 1D integral of the closed form over mu_i.
TEST(SpongeCake, IsotropicAlbedoClosedForm) {
  auto d = FibreSggx<double>::make({1, 0, 0}, 1.0);
  for (double mu : {0.1, 0.5, 0.9}) {
    const Vec3d o{std::sqrt(1 - mu * mu), 0, mu};
    const double semi = 0.5 * (1 - mu * std::log(1 + 1 / mu));
    EXPECT_NEAR(albedo(d, kInf, o, true), semi, 1e-7) << "mu " << mu;
    for (double T : {0.1, 1.0, 4.0}) {
      auto r_integrand = [&](double x) {
        return x > 0 ? 0.5 * x * -std::expm1(-T * (1 / x + 1 / mu)) / (x + mu) : 0.0;
      };
      auto t_integrand = [&](double x) {
        if (!(x > 0)) return 0.0;
        if (std::abs(x - mu) < 1e-9) return 0.5 * x * T * std::exp(-T / mu) / (mu * mu);
        return 0.5 * x * (std::exp(-T / mu) - std::exp(-T / x)) / (mu - x);
      };
      const double r_ref = test::composite_adaptive_simpson(r_integrand, 0.0, 1.0, 64, 1e-12, 30);
      const double t_ref = test::composite_adaptive_simpson(t_integrand, 0.0, 1.0, 64, 1e-12, 30);
      EXPECT_NEAR(albedo(d, T, o, true), r_ref, 1e-7) << "mu " << mu << " T " << T;
      EXPECT_NEAR(albedo(d, T, o, false), t_ref, 1e-7) << "mu " << mu << " T " << T;
      // Single scattering plus unscattered light cannot exceed the incident energy.
      EXPECT_LE(r_ref + t_ref + std::exp(-T / mu), 1.0);
    }
  }
}

// f_t through Lambda_i = Lambda_o: with the fibre along the normal, sigma(w) depends on |w_z| only,
// so mirrored directions have equal Lambda; the value must equal the closed-form limit and the
// function must be continuous (Lipschitz) as o moves away from the mirror direction.
TEST(SpongeCake, TransmissionContinuousThroughEqualLambda) {
  auto d = FibreSggx<double>::make({0, 0, 1}, 0.4);
  const double T = 1.7;
  const Vec3d i = m::normalize(Vec3d{0.5, 0.1, 0.7});
  const Vec3d o_eq{-0.3 * i.x, std::sqrt(1 - i.z * i.z - 0.09 * i.x * i.x), -i.z};
  ASSERT_NEAR(m::length(o_eq), 1.0, 1e-12);
  const double lambda = d.projected_area(i) / i.z;
  const double limit = d.D(i + o_eq) * T * std::exp(-T * lambda) / (4 * i.z * i.z);
  EXPECT_NEAR(m::spongecake_transmission(d, T, i, o_eq), limit, 1e-14 * limit);
  const double f0 = limit;
  for (double eps : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14}) {
    for (double sign : {-1.0, 1.0}) {
      Vec3d o = m::normalize(o_eq + Vec3d{0, 0, sign * eps});
      const double f = m::spongecake_transmission(d, T, i, o);
      ASSERT_TRUE(std::isfinite(f));
      EXPECT_NEAR(f, f0, 20 * eps * f0 + 1e-15 * f0) << "eps " << eps;
    }
  }
  // Float: the same continuity, to float precision.
  auto df = FibreSggx<float>::make({0, 0, 1}, 0.4f);
  const float ff0 = m::spongecake_transmission(df, float(T), Vec3f(i), Vec3f(o_eq));
  EXPECT_NEAR(ff0, f0, 1e-5 * f0);
  for (float eps : {1e-3f, 1e-5f, 1e-7f}) {
    Vec3f o = m::normalize(Vec3f(o_eq) + Vec3f{0, 0, eps});
    EXPECT_NEAR(m::spongecake_transmission(df, float(T), Vec3f(i), o), ff0,
                20 * eps * ff0 + 1e-5f * ff0);
  }
}

TEST(SpongeCake, ThinAndThickLimits) {
  std::mt19937_64 rng(3);
  for (int k = 0; k < 2000; ++k) {
    auto d = FibreSggx<double>::make(random_unit(rng), 0.05 + 0.9 * (k % 10) / 10.0);
    Vec3d i = random_unit(rng), o = random_unit(rng);
    if (std::abs(i.z) < 1e-2 || std::abs(o.z) < 1e-2) continue;
    const double first_order = d.D(i + o) / (4 * std::abs(i.z) * std::abs(o.z));
    const double tiny = 1e-9;
    // T -> 0: both lobes vanish linearly with slope D / (4 |i_z| |o_z|) (single scattering at the
    // top of a thin slab, no attenuation).
    if (i.z * o.z > 0) {
      EXPECT_EQ(m::spongecake_reflection(d, 0.0, i, o), 0.0);
      EXPECT_NEAR(m::spongecake_reflection(d, tiny, i, o) / tiny, first_order, 1e-6 * first_order);
      // T -> inf: the semi-infinite form, reached smoothly.
      const double semi =
          d.D(i + o) /
          (4 * (d.projected_area(i) * std::abs(o.z) + d.projected_area(o) * std::abs(i.z)));
      EXPECT_NEAR(m::spongecake_reflection(d, kInf, i, o), semi, 1e-14 * semi);
      EXPECT_NEAR(m::spongecake_reflection(d, 1e4, i, o), semi, 1e-14 * semi);
    } else {
      EXPECT_EQ(m::spongecake_transmission(d, 0.0, i, o), 0.0);
      EXPECT_NEAR(m::spongecake_transmission(d, tiny, i, o) / tiny, first_order,
                  1e-6 * first_order);
      EXPECT_EQ(m::spongecake_transmission(d, kInf, i, o), 0.0);
      EXPECT_LT(m::spongecake_transmission(d, 1e4, i, o), 1e-300);
    }
  }
}

// Grazing directions: |i_z| or |o_z| -> 0 approach the finite limits, never NaN.
TEST(SpongeCake, GrazingDirectionsStayFinite) {
  auto d = FibreSggx<double>::make(m::normalize(Vec3d{0.2, 0.9, 0.3}), 0.25);
  const Vec3d i = m::normalize(Vec3d{0.3, -0.2, 0.8});
  const double T = 2.0;
  for (double z : {1e-3, 1e-6, 1e-9, 1e-15, 1e-300, 0.0}) {
    const Vec3d o_up = m::normalize(Vec3d{0.6, 0.8, z});
    const Vec3d o_down = m::normalize(Vec3d{0.6, 0.8, -z});
    const double fr = m::spongecake_reflection(d, T, i, o_up);
    const double ft = m::spongecake_transmission(d, T, i, o_down);
    ASSERT_TRUE(std::isfinite(fr) && fr >= 0) << z;
    ASSERT_TRUE(std::isfinite(ft) && ft >= 0) << z;
    if (z > 0 && z <= 1e-9) {
      // f_r -> D / (4 sigma_o |i_z|); f_t -> D e^{-T Lambda_i} / (4 sigma_o |i_z|).
      const double limit_r = d.D(i + o_up) / (4 * d.projected_area(o_up) * i.z);
      const double limit_t = d.D(i + o_down) * std::exp(-T * d.projected_area(i) / i.z) /
                             (4 * d.projected_area(o_down) * i.z);
      EXPECT_NEAR(fr, limit_r, 1e-6 * limit_r) << z;
      EXPECT_NEAR(ft, limit_t, 1e-6 * limit_t) << z;
    }
    // Both cosines tiny at once: bounded by zero, no NaN.
    const Vec3d i_flat = m::normalize(Vec3d{-0.8, 0.6, z});
    ASSERT_TRUE(std::isfinite(m::spongecake_reflection(d, T, i_flat, o_up)));
    ASSERT_TRUE(std::isfinite(m::spongecake_transmission(d, T, i_flat, o_down)));
  }
  // i = o, h on the horizon, i = -o (h = 0).
  EXPECT_GT(m::spongecake_reflection(d, T, i, i), 0.0);
  const Vec3d a{0.6, 0.0, 0.8}, b{0.6, 0.0, -0.8};
  EXPECT_TRUE(std::isfinite(m::spongecake_transmission(d, T, a, b)));
  EXPECT_EQ(m::spongecake_transmission(d, T, a, -a), 0.0);
  EXPECT_EQ(m::spongecake_sample_pdf(d, -a, a), 0.0);
  // Unscattered transmittance: 1 at T = 0, e^{-T Lambda}, 0 in the plane.
  EXPECT_EQ(m::spongecake_unscattered_transmittance(d, 0.0, a), 1.0);
  EXPECT_NEAR(m::spongecake_unscattered_transmittance(d, T, a),
              std::exp(-T * d.projected_area(a) / 0.8), 1e-15);
  EXPECT_EQ(m::spongecake_unscattered_transmittance(d, T, Vec3d{1, 0, 0}), 0.0);
  EXPECT_EQ(m::spongecake_unscattered_transmittance(d, kInf, a), 0.0);
}

TEST(SpongeCake, Reciprocal) {
  std::mt19937_64 rng(4);
  for (int k = 0; k < 10000; ++k) {
    auto d = FibreSggx<double>::make(random_unit(rng), 0.01 + (k % 100) / 100.0);
    Vec3d i = random_unit(rng), o = random_unit(rng);
    const double T = 0.1 * (k % 50);
    const double fr = m::spongecake_reflection(d, T, i, o),
                 ft = m::spongecake_transmission(d, T, i, o);
    ASSERT_NEAR(fr, m::spongecake_reflection(d, T, o, i), 1e-12 * fr);
    ASSERT_NEAR(ft, m::spongecake_transmission(d, T, o, i), 1e-12 * ft);
  }
}

// Energy: single scattering (reflection + transmission) plus the unscattered transmittance never
// exceeds 1, across roughness (down to 1e-3), thickness and view; estimated with the lobe's own
// sampler (weights are bounded, so 1e5 samples give a standard error below 2e-3).
TEST(SpongeCake, WhiteFurnaceAtMostOne) {
  for (double sigma : {1e-3, 0.05, 0.3, 1.0})
    for (double T : {0.01, 1.0, 10.0, kInf})
      for (double oz : {0.05, 0.5, 1.0}) {
        auto d = FibreSggx<double>::make(m::normalize(Vec3d{0.8, 0.1, 0.3}), sigma);
        const Vec3d o = m::normalize(Vec3d{std::sqrt(1 - oz * oz), 0.3, oz});
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> uni(0.0, 1.0);
        const int n = 100000;
        double sum = 0, sum2 = 0;
        for (int k = 0; k < n; ++k) {
          Vec3d i = m::spongecake_sample(d, o, uni(rng), uni(rng));
          const double pdf = m::spongecake_sample_pdf(d, i, o);
          if (!(pdf > 0)) continue;
          const double w =
              (m::spongecake_reflection(d, T, i, o) + m::spongecake_transmission(d, T, i, o)) *
              std::abs(i.z) / pdf;
          ASSERT_TRUE(std::isfinite(w));
          ASSERT_LE(w, 1.0 + 1e-9) << "weights are bounded by the albedo";
          sum += w;
          sum2 += w * w;
        }
        const double mean = sum / n, err = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
        const double total = mean + m::spongecake_unscattered_transmittance(d, T, o);
        EXPECT_LE(total, 1.0 + 4 * err) << "sigma " << sigma << " T " << T << " oz " << oz;
        // (With sigma = 1e-3 the reflected directions lie on the fibre's specular cone i.t = -o.t,
        // which can lie entirely below the horizon: then the reflection albedo is 0.)
        if (sigma >= 0.05) {
          EXPECT_GT(mean, 0.0) << "sigma " << sigma << " T " << T << " oz " << oz;
        }
      }
}

// Chi-square of the phase-function sampler (both sides of the surface at once) against its pdf.
struct SampleCase {
  double sigma;
  Vec3d tangent, o;
};
class SpongeCakeChi2 : public ::testing::TestWithParam<SampleCase> {};

TEST_P(SpongeCakeChi2, SamplesFollowThePhaseFunction) {
  const SampleCase c = GetParam();
  auto d = FibreSggx<double>::make(c.tangent, c.sigma);
  const Vec3d o = m::normalize(c.o);
  test::Chi2Options opt;
  opt.tests = 4;
  opt.seed = 21;
  auto sampler = [&](double, double u1, double u2, Vec3d& out) {
    out = m::spongecake_sample(d, o, u1, u2);
    return true;
  };
  auto pdf = [&](const Vec3d& i) { return m::spongecake_sample_pdf(d, i, o); };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_mass, 1.0, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Cases, SpongeCakeChi2,
                         ::testing::Values(SampleCase{0.5, {1, 0, 0}, {0.3, 0.2, 0.9}},
                                           SampleCase{0.15, {0.6, 0.8, 0}, {0.8, 0.0, 0.05}},
                                           SampleCase{0.3, {0, 0, 1}, {0.1, -0.2, -0.95}},
                                           SampleCase{0.25, {0.5, 0.5, 0.7}, {-0.4, 0.6, 0.4}}));

}  // namespace

// Fibre-like SGGX (model/sggx.hpp) and its batched form (model/sggx_batch.hpp): the closed forms
// against the textbook matrix formulas, normalisation of the visible normals, stability down to
// sigma = 1e-4, and chi-square tests of the visible-normal sampler.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "model/sggx.hpp"
#include "model/sggx_batch.hpp"
#include "tests/model/chi2.hpp"

namespace {

using clothbake::model::FibreSggx;
using clothbake::model::FibreSggxBatch;
using clothbake::model::Vec3;
using clothbake::model::Vec3d;
using clothbake::model::Vec3f;
namespace test = clothbake::test;

using LD = long double;

Vec3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    Vec3d v{g(rng), g(rng), g(rng)};
    double l = clothbake::model::length(v);
    if (l > 1e-6) return v / l;
  }
}

// Textbook D = 1 / (pi sqrt|S| (m^T S^-1 m)^2) with S and its inverse formed explicitly (cofactors)
// in long double: the reference the factored form must reproduce.
LD reference_d(const Vec3d& t_in, double sigma, const Vec3d& m_in) {
  LD t[3] = {t_in.x, t_in.y, t_in.z};
  LD tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  for (auto& c : t)
    c /= tl;
  LD m[3] = {m_in.x, m_in.y, m_in.z};
  LD ml = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
  for (auto& c : m)
    c /= ml;
  LD s[3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      s[a][b] = LD(sigma) * LD(sigma) * t[a] * t[b] + ((a == b ? 1 : 0) - t[a] * t[b]);
  LD det = s[0][0] * (s[1][1] * s[2][2] - s[1][2] * s[2][1]) -
           s[0][1] * (s[1][0] * s[2][2] - s[1][2] * s[2][0]) +
           s[0][2] * (s[1][0] * s[2][1] - s[1][1] * s[2][0]);
  LD inv[3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      int a1 = (b + 1) % 3, a2 = (b + 2) % 3, b1 = (a + 1) % 3, b2 = (a + 2) % 3;
      inv[a][b] = (s[a1][b1] * s[a2][b2] - s[a1][b2] * s[a2][b1]) / det;
    }
  LD q = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      q += m[a] * inv[a][b] * m[b];
  return 1.0L / (3.141592653589793238462643383279502884L * std::sqrt(det) * q * q);
}

LD reference_projected_area(const Vec3d& t_in, double sigma, const Vec3d& w) {
  LD t[3] = {t_in.x, t_in.y, t_in.z};
  LD tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  for (auto& c : t)
    c /= tl;
  LD v[3] = {w.x, w.y, w.z};
  LD q = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      q += v[a] * (LD(sigma) * LD(sigma) * t[a] * t[b] + ((a == b ? 1 : 0) - t[a] * t[b])) * v[b];
  return std::sqrt(q);
}

TEST(Sggx, MatchesTheMatrixFormula) {
  std::mt19937_64 rng(1);
  for (double sigma : {1.0, 0.7, 0.3, 0.1, 0.03}) {
    for (int k = 0; k < 2000; ++k) {
      Vec3d t = random_unit(rng), m = random_unit(rng);
      auto d = FibreSggx<double>::make(t * 3.0, sigma);  // any tangent length
      LD ref = reference_d(t, sigma, m);
      ASSERT_NEAR(d.D(m), double(ref), 1e-11 * double(ref)) << "sigma " << sigma;
      ASSERT_NEAR(d.D_unit(m), double(ref), 1e-11 * double(ref));
      LD area = reference_projected_area(t, sigma, m);
      ASSERT_NEAR(d.projected_area(m), double(area), 1e-13);
    }
  }
}

TEST(Sggx, MatrixAndInverseAreConsistent) {
  auto d = FibreSggx<double>::make({0.3, -0.5, 0.8}, 0.25);
  auto s = d.matrix();
  auto i = d.inverse_matrix();
  double a[3][3] = {{s.xx, s.xy, s.xz}, {s.xy, s.yy, s.yz}, {s.xz, s.yz, s.zz}};
  double b[3][3] = {{i.xx, i.xy, i.xz}, {i.xy, i.yy, i.yz}, {i.xz, i.yz, i.zz}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double sum = 0;
      for (int k = 0; k < 3; ++k)
        sum += a[r][k] * b[k][c];
      EXPECT_NEAR(sum, r == c ? 1.0 : 0.0, 1e-12);
    }
  // det S = sigma^2 (the eigenvalues are sigma^2, 1, 1).
  double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
               a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
               a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  EXPECT_NEAR(std::sqrt(det), d.sqrt_det(), 1e-14);
}

TEST(Sggx, SymmetricHomogeneousAndPeakedAcrossTheFibre) {
  std::mt19937_64 rng(2);
  auto d = FibreSggx<double>::make({0, 1, 0}, 0.2);
  for (int k = 0; k < 1000; ++k) {
    Vec3d m = random_unit(rng);
    EXPECT_DOUBLE_EQ(d.D(m), d.D(-m));
    EXPECT_NEAR(d.D(m * 7.5), d.D(m), 1e-13 * d.D(m));
    EXPECT_LE(d.D(m), 1.0 / (M_PI * 0.2) * (1 + 1e-12));
    EXPECT_GE(d.D(m), 0.2 * 0.2 * 0.2 / M_PI * (1 - 1e-12));
  }
  // Maximum on the great circle perpendicular to t, minimum along t.
  EXPECT_NEAR(d.D(Vec3d{1, 0, 0}), 1.0 / (M_PI * 0.2), 1e-12);
  EXPECT_NEAR(d.D(Vec3d{0, 1, 0}), 0.008 / M_PI, 1e-15);
  EXPECT_EQ(d.D(Vec3d{0, 0, 0}), 0.0);
}

TEST(Sggx, FactoryClampsAndSanitises) {
  auto zero = FibreSggx<double>::make({0, 0, 0}, 0.5);
  EXPECT_EQ(zero.t.z, 1.0);
  auto nan_t = FibreSggx<double>::make({NAN, 0, 0}, 0.5);
  EXPECT_EQ(nan_t.t.z, 1.0);
  EXPECT_EQ(FibreSggx<double>::make({1, 0, 0}, -1.0).sigma,
            clothbake::model::kMinFibreRoughness<double>);
  EXPECT_EQ(FibreSggx<double>::make({1, 0, 0}, 5.0).sigma, 1.0);
  EXPECT_EQ(FibreSggx<double>::make({1, 0, 0}, NAN).sigma, 1.0);
}

// Integral of D(m) <w, m>^+ over the sphere, in the frame whose pole is the fibre: there D depends
// on the polar coordinate c only, and the azimuthal integral of <w, m>^+ = A cos(psi) + B (A =
// sqrt(1 - c^2) |w_perp|, B = c w_pole) has the closed form 2 (A sin psi0 + B psi0), psi0 =
// acos(-B / A). The peak of D, of width sigma around c = 0, gets its own finely split interval.
double integrate_visible_area(const FibreSggx<double>& d, const Vec3d& w) {
  auto frame = test::SphereFrame::around(d.t);
  const double w_pole = clothbake::model::dot(w, frame.n);
  const double w_perp =
      std::hypot(clothbake::model::dot(w, frame.e1), clothbake::model::dot(w, frame.e2));
  auto inner = [&](double c) {
    const double a = std::sqrt(std::max(0.0, 1 - c * c)) * w_perp, b = c * w_pole;
    double azimuthal;
    if (b >= a)
      azimuthal = 2 * M_PI * b;
    else if (b <= -a)
      azimuthal = 0;
    else {
      const double psi0 = std::acos(-b / a);
      azimuthal = 2 * (a * std::sin(psi0) + b * psi0);
    }
    return azimuthal * d.D(frame.direction(c, 0.0));
  };
  const double band = std::min(0.5, 30 * d.sigma);
  return test::composite_adaptive_simpson(inner, -1.0, -band, 16, 1e-12, 30) +
         test::composite_adaptive_simpson(inner, -band, band, 256, 1e-12, 30) +
         test::composite_adaptive_simpson(inner, band, 1.0, 16, 1e-12, 30);
}

TEST(Sggx, VisibleNormalsIntegrateToProjectedArea) {
  const Vec3d t = clothbake::model::normalize(Vec3d{0.6, 0.0, 0.8});
  for (double sigma : {1.0, 0.5, 0.1, 0.02, 1e-3}) {
    auto d = FibreSggx<double>::make(t, sigma);
    for (Vec3d w :
         {Vec3d{0, 0, 1}, t, Vec3d{0, 1, 0}, clothbake::model::normalize(Vec3d{1, 2, -0.5}),
          clothbake::model::normalize(Vec3d{-0.8, 0, 0.6})}) {
      const double area = d.projected_area(w);
      const double integral = integrate_visible_area(d, w);
      EXPECT_NEAR(integral, area, 1e-8 * area)
          << "sigma " << sigma << " w " << w.x << "," << w.y << "," << w.z;
    }
  }
}

TEST(Sggx, IsotropicCaseIntegratesToFour) {
  auto d = FibreSggx<double>::make({0, 0, 1}, 1.0);
  auto f = [&](const Vec3d& m) { return d.D(m); };
  EXPECT_NEAR(test::integrate_sphere(f, test::SphereFrame{}, 4, 8, 1e-10), 4.0, 1e-9);
  // And the absolute-cosine integral is 2 sigma(w) = 2.
  Vec3d w = clothbake::model::normalize(Vec3d{0.3, 0.2, 0.9});
  auto g = [&](const Vec3d& m) { return std::abs(clothbake::model::dot(w, m)) * d.D(m); };
  EXPECT_NEAR(test::integrate_sphere(g, test::SphereFrame::around(w), 4, 8, 1e-10), 2.0, 1e-7);
}

// Float evaluation at sigma = 1e-3 and 1e-4: finite, non-negative, within float precision of the
// double values; projected area never below sigma |w|.
TEST(Sggx, StableInFloatForTinyRoughness) {
  std::mt19937_64 rng(3);
  for (double sigma : {1e-3, 1e-4}) {
    for (int k = 0; k < 20000; ++k) {
      Vec3d t = random_unit(rng), m = random_unit(rng);
      if (k % 4 == 0) m = clothbake::model::normalize(t + random_unit(rng) * 1e-5);  // near t
      // The double reference sees the same (float-rounded) inputs.
      const Vec3f tf(t), mf(m);
      t = Vec3d(tf);
      m = Vec3d(mf);
      auto dd = FibreSggx<double>::make(t, sigma);
      auto df = FibreSggx<float>::make(tf, float(sigma));
      const float vf = df.D(mf);
      const double vd = dd.D(m);
      ASSERT_TRUE(std::isfinite(vf));
      ASSERT_GE(vf, 0.0f);
      ASSERT_LE(vf, float(1.0 / (M_PI * sigma)) * 1.001f);
      // Float rounding of c = t.m (a few ulps, absolute) is amplified by the condition number
      // 2c / (sigma^2 + c^2) <= 1 / sigma of q = sigma^2 + (1 - sigma^2) c^2: the honest bound.
      const double c = std::abs(clothbake::model::dot(t, m));
      const double tol = 1e-5 + 2.5e-6 * 2 * c / (sigma * sigma + c * c);
      ASSERT_NEAR(vf, vd, tol * vd) << "sigma " << sigma << " c " << c;
      const float area = df.projected_area(mf);
      ASSERT_GE(area, float(sigma) * 0.999f);
      ASSERT_NEAR(area, dd.projected_area(m), 3e-7 + 1e-6 * dd.projected_area(m));
      Vec3f s = df.sample_vndf(mf, float(k % 97) / 97.f, float(k % 89) / 89.f);
      ASSERT_TRUE(std::isfinite(s.x + s.y + s.z));
      ASSERT_NEAR(clothbake::model::length(s), 1.0f, 1e-5f);
      ASSERT_GE(clothbake::model::dot(s, mf), -1e-5f);
    }
  }
}

TEST(Sggx, BatchedEvaluationMatchesScalar) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> uni(0.001, 1.0);
  const std::size_t n = 1037;  // not a multiple of a vector width
  FibreSggxBatch<float> batch;
  std::vector<FibreSggx<float>> texels;
  for (std::size_t i = 0; i < n; ++i) {
    texels.push_back(FibreSggx<float>::make(Vec3f(random_unit(rng)), float(uni(rng))));
    batch.push_back(texels.back());
  }
  std::vector<float> out(n), acc(n, 1.0f);
  const Vec3f h = Vec3f(random_unit(rng));
  clothbake::model::sggx_d_over_texels(batch, h, out.data());
  clothbake::model::sggx_d_over_texels_accumulate(batch, h, 0.5f, acc.data());
  for (std::size_t i = 0; i < n; ++i) {
    const float ref = texels[i].D_unit(h);
    ASSERT_NEAR(out[i], ref, 1e-6f * ref);
    ASSERT_NEAR(acc[i], 1.0f + 0.5f * ref, 1e-6f * (1.0f + ref));
  }
  std::vector<float> hx(n), hy(n), hz(n), dirs(n);
  for (std::size_t j = 0; j < n; ++j) {
    Vec3f w = Vec3f(random_unit(rng));
    hx[j] = w.x, hy[j] = w.y, hz[j] = w.z;
  }
  clothbake::model::sggx_d_over_directions(texels[5], n, hx.data(), hy.data(), hz.data(),
                                           dirs.data());
  for (std::size_t j = 0; j < n; ++j) {
    const float ref = texels[5].D_unit(Vec3f{hx[j], hy[j], hz[j]});
    ASSERT_NEAR(dirs[j], ref, 1e-6f * ref);
  }
}

// Chi-square: visible-normal samples against D_w. Cases: rough, medium at a grazing view, and a
// fibre parallel to the normal seen from above (the view along the fibre).
struct VndfCase {
  double sigma;
  Vec3d tangent, w;
};

class VndfChi2 : public ::testing::TestWithParam<VndfCase> {};

TEST_P(VndfChi2, SamplesFollowTheVisibleNormalDensity) {
  const VndfCase c = GetParam();
  auto d = FibreSggx<double>::make(c.tangent, c.sigma);
  const Vec3d w = clothbake::model::normalize(c.w);
  test::Chi2Options opt;
  opt.tests = 4;
  opt.seed = 11;
  auto sampler = [&](double, double u1, double u2, Vec3d& out) {
    out = d.sample_vndf(w, u1, u2);
    return true;
  };
  auto pdf = [&](const Vec3d& m) { return d.vndf_pdf(w, m); };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_mass, 1.0, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Cases, VndfChi2,
                         ::testing::Values(VndfCase{0.8, {1, 0, 0}, {0.3, 0.1, 0.9}},
                                           VndfCase{0.3, {0.6, 0.8, 0}, {0.9, -0.2, 0.1}},
                                           VndfCase{0.12, {0, 0, 1}, {0, 0, 1}},
                                           VndfCase{0.2, {0.3, -0.4, 0.866}, {-0.5, 0.5, -0.7}}));

// The harness must reject a sampler whose density is not the one claimed: sigma 0.3 samples
// against the sigma 0.36 density.
TEST(VndfChi2Wrong, WrongRoughnessFails) {
  auto sample_d = FibreSggx<double>::make({1, 0, 0}, 0.3);
  auto claim_d = FibreSggx<double>::make({1, 0, 0}, 0.36);
  const Vec3d w = clothbake::model::normalize(Vec3d{0.2, 0.3, 0.9});
  test::Chi2Options opt;
  opt.seed = 5;
  auto sampler = [&](double, double u1, double u2, Vec3d& out) {
    out = sample_d.sample_vndf(w, u1, u2);
    return true;
  };
  auto pdf = [&](const Vec3d& m) { return claim_d.vndf_pdf(w, m); };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_FALSE(r.passed) << r.message;
  EXPECT_LT(r.p_value, 1e-12);
}

}  // namespace

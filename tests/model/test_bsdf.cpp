// The full local BSDF (model/cloth_bsdf.hpp): lobe assembly of Eq. 3-4, reciprocity, energy,
// chi-square tests of each sampling technique and of the whole mixture (Sec. 5.1), the estimator
// weights, stiff parameters, and parameter validation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "model/cloth_bsdf.hpp"
#include "model/parameter_text.hpp"
#include "tests/model/chi2.hpp"

namespace {

namespace m = clothbake::model;
namespace test = clothbake::test;
using m::ClothBsdf;
using m::Lobe;
using m::Rgb;
using m::Technique;
using m::TexelParams;
using m::Vec3d;
using m::Vec3f;

const double kInf = std::numeric_limits<double>::infinity();

Vec3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    Vec3d v{g(rng), g(rng), g(rng)};
    double l = m::length(v);
    if (l > 1e-6) return v / l;
  }
}

TexelParams<double> typical() {
  TexelParams<double> p;
  p.tangent = {0.8, 0.2, 0.3};
  p.roughness = 0.3;
  p.optical_thickness = 2.0;
  p.specular_albedo = {0.7, 0.6, 0.5};
  p.diffuse_reflectance = {0.15, 0.2, 0.25};
  p.diffuse_transmittance = {0.1, 0.15, 0.2};
  p.gap = 0.8;
  p.sheen_color = {0.5, 0.4, 0.3};
  p.sheen_roughness = 0.4;
  return p;
}

void expect_rgb_near(const Rgb<double>& a, const Rgb<double>& b, double tol, const char* what) {
  EXPECT_NEAR(a.r, b.r, tol * std::max(1.0, std::abs(b.r))) << what;
  EXPECT_NEAR(a.g, b.g, tol * std::max(1.0, std::abs(b.g))) << what;
  EXPECT_NEAR(a.b, b.b, tol * std::max(1.0, std::abs(b.b))) << what;
}

// Eq. 3-4 assembled by hand from the component functions.
TEST(ClothBsdf, LobesFollowEquationFour) {
  const TexelParams<double> p = typical();
  const ClothBsdf<double> bsdf(p);
  const auto d = m::FibreSggx<double>::make(p.tangent, p.roughness);
  std::mt19937_64 rng(1);
  for (int k = 0; k < 2000; ++k) {
    const Vec3d i = random_unit(rng), o = random_unit(rng);
    const double v = (k % 5) / 4.0;
    const auto f = bsdf.eval(i, o, v);
    // Sheen on the side of o (mirrored from below).
    const Vec3d ms{i.x, i.y, -i.z}, mo{o.x, o.y, -o.z};
    const double sheen =
        o.z < 0 ? m::sheen_eval(ms, mo, p.sheen_roughness) : m::sheen_eval(i, o, p.sheen_roughness);
    const double R = m::sheen_albedo(std::abs(o.z), p.sheen_roughness);
    const Rgb<double> t_sheen = Rgb<double>(1.0) - p.sheen_color * R;
    const Rgb<double> base = t_sheen * (p.gap * v);
    expect_rgb_near(
        f.specular_reflection,
        base * p.specular_albedo * m::spongecake_reflection(d, p.optical_thickness, i, o), 1e-14,
        "specular_reflection");
    expect_rgb_near(
        f.specular_transmission,
        base * p.specular_albedo * m::spongecake_transmission(d, p.optical_thickness, i, o), 1e-14,
        "specular_transmission");
    const bool same = i.z * o.z > 0;
    expect_rgb_near(f.diffuse_reflection, base * p.diffuse_reflectance * (same ? 1 / M_PI : 0.0),
                    1e-14, "diffuse_reflection");
    expect_rgb_near(f.diffuse_transmission,
                    base * p.diffuse_transmittance * (same ? 0.0 : 1 / M_PI), 1e-14,
                    "diffuse_transmission");
    expect_rgb_near(f.sheen, p.sheen_color * (v * sheen), 1e-14, "sheen");
    expect_rgb_near(f.delta_transmission, t_sheen * ((1 - p.gap) * v), 1e-14, "delta");
    expect_rgb_near(f.total,
                    f.specular_reflection + f.specular_transmission + f.diffuse_reflection +
                        f.diffuse_transmission + f.sheen,
                    1e-14, "total");
    EXPECT_EQ(f[Lobe::SpecularTransmission].g, f.specular_transmission.g);
    EXPECT_EQ(f[Lobe::DiffuseReflection].b, f.diffuse_reflection.b);
    EXPECT_EQ(f[Lobe::Sheen].r, f.sheen.r);
    EXPECT_EQ(f[Lobe::DeltaTransmission].r, f.delta_transmission.r);
  }
  // Lobe names round-trip.
  for (int l = 0; l < m::kLobeCount; ++l) {
    Lobe parsed;
    ASSERT_TRUE(m::parse_lobe(m::lobe_name(Lobe(l)), parsed));
    EXPECT_EQ(parsed, Lobe(l));
  }
  Lobe unused;
  EXPECT_FALSE(m::parse_lobe("specular", unused));
}

TEST(ClothBsdf, ReciprocalWithoutSheen) {
  TexelParams<double> p = typical();
  p.sheen_color = Rgb<double>(0.0);
  std::mt19937_64 rng(2);
  for (double sigma : {1e-3, 0.1, 0.5, 1.0})
    for (double T : {0.0, 0.3, 3.0, kInf}) {
      p.roughness = sigma;
      p.optical_thickness = T;
      const ClothBsdf<double> bsdf(p);
      for (int k = 0; k < 500; ++k) {
        const Vec3d i = random_unit(rng), o = random_unit(rng);
        const auto a = bsdf.eval(i, o).total, b = bsdf.eval(o, i).total;
        ASSERT_NEAR(a.r, b.r, 1e-12 * a.r);
        ASSERT_NEAR(a.g, b.g, 1e-12 * a.g);
        ASSERT_NEAR(a.b, b.b, 1e-12 * a.b);
      }
    }
}

// The diffuse lobes' albedos are exactly T_sheen I R_d and T_sheen I T_d (quadrature).
TEST(ClothBsdf, DiffuseAlbedosAreTheirParameters) {
  TexelParams<double> p = typical();
  p.specular_albedo = Rgb<double>(0.0);
  const ClothBsdf<double> bsdf(p);
  for (Vec3d o : {Vec3d{0, 0, 1}, m::normalize(Vec3d{0.5, 0.5, -0.3})}) {
    auto f_r = [&](const Vec3d& i) { return bsdf.eval(i, o).diffuse_reflection.g * std::abs(i.z); };
    auto f_t = [&](const Vec3d& i) {
      return bsdf.eval(i, o).diffuse_transmission.g * std::abs(i.z);
    };
    const double ts = bsdf.sheen_transmittance(o).g;
    EXPECT_NEAR(test::integrate_sphere(f_r, test::SphereFrame{}, 4, 8, 1e-12),
                ts * p.gap * p.diffuse_reflectance.g, 1e-9);
    EXPECT_NEAR(test::integrate_sphere(f_t, test::SphereFrame{}, 4, 8, 1e-12),
                ts * p.gap * p.diffuse_transmittance.g, 1e-9);
  }
}

// Sheen integration (Eq. 4): the sheen lobe is colour * sheen_eval and every other lobe is scaled
// by T_sheen = 1 - colour * R(|o_z|); seen from below, the mirrored configuration.
TEST(ClothBsdf, SheenLayering) {
  TexelParams<double> with = typical(), without = typical();
  without.sheen_color = Rgb<double>(0.0);
  const ClothBsdf<double> a(with), b(without);
  std::mt19937_64 rng(3);
  for (int k = 0; k < 1000; ++k) {
    const Vec3d i = random_unit(rng), o = random_unit(rng);
    const auto fa = a.eval(i, o), fb = b.eval(i, o);
    const double R = m::sheen_albedo(std::abs(o.z), with.sheen_roughness);
    const Rgb<double> ts = Rgb<double>(1.0) - with.sheen_color * R;
    expect_rgb_near(fa.total - fa.sheen, fb.total * ts, 1e-13, "base scaled by T_sheen");
    expect_rgb_near(fa.delta_transmission, fb.delta_transmission * ts, 1e-13, "delta scaled");
    // Mirror symmetry of the whole BSDF (the tangent mirrors too).
    TexelParams<double> mirrored = with;
    mirrored.tangent.z = -mirrored.tangent.z;
    const ClothBsdf<double> c(mirrored);
    const auto fc = c.eval(Vec3d{i.x, i.y, -i.z}, Vec3d{o.x, o.y, -o.z});
    expect_rgb_near(fc.total, fa.total, 1e-12, "mirror image");
  }
}

// The sheen table follows TexelParams::sheen_convention (published by default), in the lobe, in
// T_sheen and in the sheen technique's probability; an out-of-range value acts as Published.
TEST(ClothBsdf, SheenConventionSelectsTheTable) {
  TexelParams<double> p = typical();
  EXPECT_EQ(p.sheen_convention, m::SheenConvention::Published);
  p.sheen_color = Rgb<double>(1.0);
  p.sheen_roughness = 1.0 / 31.0;  // where the two tables differ most
  const Vec3d o = m::normalize(Vec3d{0.999, 0.0, 0.02}), i = m::normalize(Vec3d{-0.5, 0.1, 0.3});
  for (m::SheenConvention c : {m::SheenConvention::Published, m::SheenConvention::Converged}) {
    p.sheen_convention = c;
    const ClothBsdf<double> bsdf(p);
    const double R = m::sheen_albedo(o.z, p.sheen_roughness, c);
    EXPECT_NEAR(bsdf.sheen_transmittance(o).g, 1.0 - R, 1e-15);
    EXPECT_NEAR(bsdf.eval(i, o).sheen.g, m::sheen_eval(i, o, p.sheen_roughness, c), 1e-15);
  }
  p.sheen_convention = m::SheenConvention::Converged;
  const double t_converged = ClothBsdf<double>(p).sheen_transmittance(o).g;
  p.sheen_convention = m::SheenConvention(9);
  const double t_other = ClothBsdf<double>(p).sheen_transmittance(o).g;
  p.sheen_convention = m::SheenConvention::Published;
  const double t_published = ClothBsdf<double>(p).sheen_transmittance(o).g;
  EXPECT_EQ(t_other, t_published);
  EXPECT_GT(t_published - t_converged, 0.2);  // 0.27 at this o
}

// White furnace: with alpha + R_d + T_d = 1 and white sheen, the integral of f^ |i_z| plus the
// delta weight is at most 1, for every lobe and for the sum, across roughness, thickness, gap and
// view. Estimated with the BSDF's own sampler (weights bounded), 4e4 samples per case.
TEST(ClothBsdf, WhiteFurnaceAtMostOne) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (double sigma : {1e-3, 0.1, 0.6})
    for (double T : {0.05, 2.0, kInf})
      for (double gap : {1.0, 0.5})
        for (double oz : {0.1, -0.7, 1.0}) {
          TexelParams<double> p;
          p.tangent = {0.3, 0.9, 0.2};
          p.roughness = sigma;
          p.optical_thickness = T;
          p.specular_albedo = Rgb<double>(0.6);
          p.diffuse_reflectance = Rgb<double>(0.25);
          p.diffuse_transmittance = Rgb<double>(0.15);
          p.gap = gap;
          p.sheen_color = Rgb<double>(1.0);
          p.sheen_roughness = 0.5;
          ASSERT_LE(m::energy_excess(p), 1e-15);
          const ClothBsdf<double> bsdf(p);
          const Vec3d o = m::normalize(Vec3d{std::sqrt(1 - oz * oz), -0.2, oz});
          const int n = 40000;
          double lobe_sum[m::kLobeCount] = {}, total = 0, total2 = 0;
          for (int k = 0; k < n; ++k) {
            const auto s = bsdf.sample(o, uni(rng), uni(rng), uni(rng));
            if (!s.valid) continue;
            ASSERT_TRUE(std::isfinite(s.weight.r) && s.weight.r >= 0);
            total += s.weight.r;
            total2 += s.weight.r * s.weight.r;
            if (s.is_delta) {
              lobe_sum[int(Lobe::DeltaTransmission)] += s.weight.r;
              continue;
            }
            const auto f = bsdf.eval(s.wi, o);
            for (int l = 0; l < m::kLobeCount; ++l)
              if (Lobe(l) != Lobe::DeltaTransmission)
                lobe_sum[l] += f[Lobe(l)].r * std::abs(s.wi.z) / s.pdf;
          }
          const double mean = total / n;
          const double err = std::sqrt(std::max(0.0, total2 / n - mean * mean) / n);
          EXPECT_LE(mean, 1.0 + 4 * err + 1e-12)
              << "sigma " << sigma << " T " << T << " gap " << gap << " oz " << oz;
          for (int l = 0; l < m::kLobeCount; ++l)
            EXPECT_LE(lobe_sum[l] / n, 1.0 + 4 * err);
          // The delta lobe is exact: T_sheen (1 - I), up to sampling noise of its selection.
          const double expected_delta = bsdf.sheen_transmittance(o).r * (1 - gap);
          EXPECT_NEAR(lobe_sum[int(Lobe::DeltaTransmission)] / n, expected_delta,
                      5 * std::sqrt(expected_delta / n) + 1e-12);
          // White sheen reflects something at every view from either side (the committed table
          // is fitted: R > 0 for sheen roughness 0.5).
          EXPECT_GT(lobe_sum[int(Lobe::Sheen)], 0.0);
        }
}

// The estimator weights are what they claim: weight = f^ |i_z| / pdf with pdf the mixture density
// that pdf() returns, and both the MIS weight and the paper's per-lobe weight are unbiased (their
// means agree within Monte Carlo error).
TEST(ClothBsdf, SampleWeightsAreConsistentAndUnbiased) {
  const TexelParams<double> p = typical();
  const ClothBsdf<double> bsdf(p);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (Vec3d o : {m::normalize(Vec3d{0.4, 0.1, 0.8}), m::normalize(Vec3d{-0.2, 0.5, -0.3})}) {
    const int n = 200000;
    double sw = 0, sw2 = 0, sl = 0, sl2 = 0;
    int delta = 0;
    const auto pa = bsdf.technique_probabilities(o);
    for (int k = 0; k < n; ++k) {
      const auto s = bsdf.sample(o, uni(rng), uni(rng), uni(rng));
      if (!s.valid) continue;
      if (s.is_delta) {
        ++delta;
        EXPECT_EQ(s.wi.x, -o.x);
        EXPECT_NEAR(s.pdf, pa[Technique::Delta], 1e-15);
      } else if (k % 16 == 0) {
        const double pdf = bsdf.pdf(s.wi, o);
        ASSERT_NEAR(s.pdf, pdf, 1e-12 * pdf);
        const auto f = bsdf.eval(s.wi, o).total;
        ASSERT_NEAR(s.weight.g, f.g * std::abs(s.wi.z) / pdf, 1e-12 * s.weight.g + 1e-300);
      }
      sw += s.weight.g;
      sw2 += s.weight.g * s.weight.g;
      sl += s.lobe_weight.g;
      sl2 += s.lobe_weight.g * s.lobe_weight.g;
    }
    const double mw = sw / n, ml = sl / n;
    const double ew = std::sqrt((sw2 / n - mw * mw) / n), el = std::sqrt((sl2 / n - ml * ml) / n);
    EXPECT_NEAR(mw, ml, 5 * std::hypot(ew, el));
    // The delta technique is chosen with probability p_a(delta) (binomial, 5 standard deviations).
    const double pd = pa[Technique::Delta];
    EXPECT_NEAR(double(delta) / n, pd, 5 * std::sqrt(pd * (1 - pd) / n));
  }
}

TEST(ClothBsdf, TechniqueProbabilitiesFollowTheAttenuations) {
  TexelParams<double> p = typical();
  p.sheen_color = Rgb<double>(0.0);
  const ClothBsdf<double> bsdf(p);
  const Vec3d o = m::normalize(Vec3d{0.3, 0.3, 0.6});
  const auto pa = bsdf.technique_probabilities(o);
  double sum = 0;
  for (double v : pa.p)
    sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-15);
  const double interact = -std::expm1(-p.optical_thickness * m::spongecake_lambda(bsdf.sggx(), o));
  const double a_spec = p.gap * p.specular_albedo.mean() * interact;
  const double a_dr = p.gap * p.diffuse_reflectance.mean(),
               a_dt = p.gap * p.diffuse_transmittance.mean();
  const double a_delta = 1 - p.gap, a_sum = a_spec + a_dr + a_dt + a_delta;
  EXPECT_NEAR(pa[Technique::Specular], a_spec / a_sum, 1e-15);
  EXPECT_NEAR(pa[Technique::DiffuseReflection], a_dr / a_sum, 1e-15);
  EXPECT_NEAR(pa[Technique::DiffuseTransmission], a_dt / a_sum, 1e-15);
  EXPECT_NEAR(pa[Technique::Delta], a_delta / a_sum, 1e-15);
  EXPECT_EQ(pa[Technique::Sheen], 0.0);
}

// Chi-square of the whole mixture: the density the sampler realises is pdf(); delta samples are
// the missing mass 1 - integral(pdf) = p_a(delta).
struct MixtureCase {
  double sigma, thickness, gap, sheen;
  Vec3d tangent, o;
};
class MixtureChi2 : public ::testing::TestWithParam<MixtureCase> {};

TEST_P(MixtureChi2, SamplesFollowTheMixtureDensity) {
  const MixtureCase c = GetParam();
  TexelParams<double> p = typical();
  p.roughness = c.sigma;
  p.optical_thickness = c.thickness;
  p.gap = c.gap;
  p.tangent = c.tangent;
  p.sheen_color = Rgb<double>(c.sheen);
  const ClothBsdf<double> bsdf(p);
  const Vec3d o = m::normalize(c.o);
  test::Chi2Options opt;
  opt.tests = 4;
  opt.seed = 31;
  auto sampler = [&](double u0, double u1, double u2, Vec3d& out) {
    const auto s = bsdf.sample(o, u0, u1, u2);
    if (!s.valid || s.is_delta) return false;
    out = s.wi;
    return true;
  };
  auto pdf = [&](const Vec3d& i) { return bsdf.pdf(i, o); };
  auto r = test::chi2_test(sampler, pdf, opt);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_NEAR(r.pdf_mass, 1.0 - bsdf.technique_probabilities(o)[Technique::Delta], 1e-4);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, MixtureChi2,
    ::testing::Values(MixtureCase{0.3, 2.0, 1.0, 0.0, {0.8, 0.2, 0.3}, {0.3, 0.1, 0.9}},
                      MixtureCase{0.1, 0.5, 0.6, 0.5, {0.0, 1.0, 0.0}, {0.5, -0.4, -0.4}},
                      MixtureCase{0.5, kInf, 0.9, 0.8, {0.0, 0.0, 1.0}, {0.7, 0.0, 0.3}},
                      MixtureCase{0.2, 1.0, 0.3, 0.3, {0.6, 0.6, 0.5}, {-0.1, 0.2, 0.97}}));

// Chi-square of the techniques that the other files do not cover: the cosine lobes and the sheen
// LTC through the mirroring used for views from below.
class TechniqueChi2 : public ::testing::TestWithParam<int> {};

TEST_P(TechniqueChi2, SamplesFollowTheTechniqueDensity) {
  const Technique technique = Technique(GetParam());
  const ClothBsdf<double> bsdf(typical());
  // A texel whose only technique is sheen: its sample() runs ClothBsdf's own sheen path (with the
  // mirroring for views from below), not a copy of it.
  TexelParams<double> sheen_params = typical();
  sheen_params.specular_albedo = sheen_params.diffuse_reflectance =
      sheen_params.diffuse_transmittance = Rgb<double>(0.0);
  sheen_params.gap = 1.0;
  const ClothBsdf<double> sheen_only(sheen_params);
  for (Vec3d o : {m::normalize(Vec3d{0.3, 0.4, 0.6}), m::normalize(Vec3d{0.6, -0.3, -0.5})}) {
    ASSERT_EQ(sheen_only.technique_probabilities(o)[Technique::Sheen], 1.0);
    test::Chi2Options opt;
    opt.tests = 6;
    opt.seed = 41 + GetParam();
    auto sampler = [&](double, double u1, double u2, Vec3d& out) {
      switch (technique) {
        case Technique::DiffuseReflection:
          out = m::lambert_reflection_sample(o, u1, u2);
          break;
        case Technique::DiffuseTransmission:
          out = m::lambert_transmission_sample(o, u1, u2);
          break;
        case Technique::Sheen: {
          const auto s = sheen_only.sample(o, 0.5, u1, u2);
          if (!s.valid || s.technique != Technique::Sheen) return false;
          out = s.wi;
          break;
        }
        default:
          return false;
      }
      return m::length(out) > 0.5;
    };
    auto pdf = [&](const Vec3d& i) { return bsdf.technique_pdf(technique, i, o); };
    auto r = test::chi2_test(sampler, pdf, opt);
    EXPECT_TRUE(r.passed) << m::technique_name(technique) << ": " << r.message;
    EXPECT_NEAR(r.pdf_mass, 1.0, 1e-4);
  }
}

INSTANTIATE_TEST_SUITE_P(Techniques, TechniqueChi2,
                         ::testing::Values(int(Technique::Sheen), int(Technique::DiffuseReflection),
                                           int(Technique::DiffuseTransmission)));

// Stiff parameters and directions, float and double: every lobe, pdf and sample weight finite and
// >= 0.
template <class T>
void check_stiff() {
  const T inf = std::numeric_limits<T>::infinity();
  std::vector<m::Vec3<T>> dirs = {{0, 0, 1},
                                  {0, 0, -1},
                                  {1, 0, 0},
                                  m::normalize(m::Vec3<T>{1, 0, T(1e-7)}),
                                  m::normalize(m::Vec3<T>{1, 1, T(-1e-7)}),
                                  m::normalize(m::Vec3<T>{0.3, -0.4, 0.5}),
                                  m::normalize(m::Vec3<T>{-0.3, 0.4, -0.5}),
                                  m::normalize(m::Vec3<T>{0.6, 0, 0.8}),
                                  m::normalize(m::Vec3<T>{0.6, 0, -0.8}),
                                  m::normalize(m::Vec3<T>{0, T(1e-30), 1})};
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (T sigma : {T(1e-4), T(1e-3), T(0.01), T(0.3), T(1)})
    for (T thickness : {T(0), T(1e-6), T(1), T(1e3), inf})
      for (m::Vec3<T> tangent :
           {m::Vec3<T>{0, 0, 1}, m::Vec3<T>{1, 0, 0}, m::Vec3<T>{0.3, 0.3, 0.9}})
        for (T albedo : {T(0), T(1)}) {
          TexelParams<T> p;
          p.tangent = tangent;
          p.roughness = sigma;
          p.optical_thickness = thickness;
          p.specular_albedo = Rgb<T>(albedo);
          p.diffuse_reflectance = Rgb<T>(albedo * T(0.2));
          p.diffuse_transmittance = Rgb<T>(0);
          p.gap = T(0.9);
          p.sheen_color = Rgb<T>(albedo);
          const ClothBsdf<T> bsdf(p);
          for (const auto& i : dirs)
            for (const auto& o : dirs) {
              const auto f = bsdf.eval(i, o);
              for (int l = 0; l < m::kLobeCount; ++l) {
                const Rgb<T> v = f[Lobe(l)];
                ASSERT_TRUE(std::isfinite(v.r) && v.r >= 0 && std::isfinite(v.b) && v.b >= 0)
                    << m::lobe_name(Lobe(l)) << " sigma " << sigma << " T " << thickness;
              }
              ASSERT_TRUE(std::isfinite(f.total.g) && f.total.g >= 0);
              const T pdf = bsdf.pdf(i, o);
              ASSERT_TRUE(std::isfinite(pdf) && pdf >= 0)
                  << "sigma " << sigma << " T " << thickness;
            }
          for (const auto& o : dirs)
            for (int k = 0; k < 20; ++k) {
              const auto s = bsdf.sample(o, T(uni(rng)), T(uni(rng)), T(uni(rng)));
              if (!s.valid) continue;
              ASSERT_TRUE(std::isfinite(s.weight.r) && s.weight.r >= 0);
              ASSERT_TRUE(std::isfinite(s.lobe_weight.r) && s.lobe_weight.r >= 0);
              ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf > 0);
              ASSERT_NEAR(m::length(s.wi), T(1), T(1e-4));
            }
        }
}

TEST(ClothBsdf, StiffCasesStayFiniteDouble) {
  check_stiff<double>();
}
TEST(ClothBsdf, StiffCasesStayFiniteFloat) {
  check_stiff<float>();
}

TEST(ClothBsdf, ZeroAlbedoAndFullGap) {
  TexelParams<double> p;
  p.specular_albedo = p.diffuse_reflectance = p.diffuse_transmittance = Rgb<double>(0);
  p.sheen_color = Rgb<double>(0);
  p.gap = 1.0;
  const ClothBsdf<double> dark(p);
  const Vec3d o{0, 0.6, 0.8};
  EXPECT_FALSE(dark.sample(o, 0.5, 0.5, 0.5).valid);
  EXPECT_EQ(dark.eval(Vec3d{0.6, 0, 0.8}, o).total.r, 0.0);
  EXPECT_EQ(dark.pdf(Vec3d{0.6, 0, 0.8}, o), 0.0);
  // A pure gap: only the delta lobe, with weight 1 and probability 1.
  p = TexelParams<double>{};
  p.gap = 0.0;
  const ClothBsdf<double> gap(p);
  const auto s = gap.sample(o, 0.3, 0.5, 0.5);
  ASSERT_TRUE(s.valid && s.is_delta);
  EXPECT_EQ(s.pdf, 1.0);
  EXPECT_EQ(s.weight.g, 1.0);
  EXPECT_EQ(gap.eval(Vec3d{0.6, 0, 0.8}, o).total.g, 0.0);
  EXPECT_EQ(gap.eval(-o, o).delta_transmission.g, 1.0);
}

TEST(ClothBsdf, ValidationNamesTheField) {
  auto problem = [](auto mutate) {
    TexelParams<double> p;
    mutate(p);
    return m::validate_texel_params(p).field;
  };
  EXPECT_EQ(problem([](auto&) {}), "");
  EXPECT_EQ(problem([](auto& p) { p.tangent = {0, 0, 0}; }), "tangent");
  EXPECT_EQ(problem([](auto& p) { p.tangent = {NAN, 0, 1}; }), "tangent");
  EXPECT_EQ(problem([](auto& p) { p.roughness = -0.1; }), "roughness");
  EXPECT_EQ(problem([](auto& p) { p.roughness = 0; }), "roughness");
  EXPECT_EQ(problem([](auto& p) { p.roughness = 1.5; }), "roughness");
  EXPECT_EQ(problem([](auto& p) { p.optical_thickness = -1; }), "optical_thickness");
  EXPECT_EQ(problem([](auto& p) { p.optical_thickness = NAN; }), "optical_thickness");
  EXPECT_EQ(problem([](auto& p) { p.optical_thickness = kInf; }), "");
  EXPECT_EQ(problem([](auto& p) { p.specular_albedo.g = 1.2; }), "specular_albedo");
  EXPECT_EQ(problem([](auto& p) { p.diffuse_reflectance.b = -0.1; }), "diffuse_reflectance");
  EXPECT_EQ(problem([](auto& p) { p.diffuse_transmittance.r = NAN; }), "diffuse_transmittance");
  EXPECT_EQ(problem([](auto& p) { p.gap = 2; }), "gap");
  EXPECT_EQ(problem([](auto& p) { p.sheen_color.r = 3; }), "sheen_color");
  EXPECT_EQ(problem([](auto& p) { p.sheen_roughness = -1; }), "sheen_roughness");
  TexelParams<double> p;
  p.specular_albedo = Rgb<double>(0.8);
  p.diffuse_reflectance = Rgb<double>(0.3);
  p.diffuse_transmittance = Rgb<double>(0.2);
  EXPECT_NEAR(m::energy_excess(p), 0.3, 1e-15);
}

}  // namespace

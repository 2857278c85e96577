// model::lobe_integral_cos (model/lobe_integral.hpp) against nested adaptive quadrature of the same
// integral, at a moderate roughness and at roughness 1e-3 near grazing, where an N² pixel sum is
// off by up to 20 % (docs/model.md, "Lobe integrals").
#include <gtest/gtest.h>

#include <cmath>

#include "model/cloth_bsdf.hpp"
#include "model/directions.hpp"
#include "model/lobe_integral.hpp"
#include "tests/model/chi2.hpp"

namespace {

namespace m = clothbake::model;
namespace test = clothbake::test;
using m::Vec3d;

m::ClothBsdf<double> specular_only(double roughness) {
  m::TexelParams<double> p;
  p.tangent = {1, 0, 0};
  p.roughness = roughness;
  p.optical_thickness = 1.0;
  p.specular_albedo = m::Rgb<double>{0.9};
  p.diffuse_reflectance = m::Rgb<double>{0.0};
  p.diffuse_transmittance = m::Rgb<double>{0.0};
  return m::ClothBsdf<double>(p);
}

double specular_reflection(const m::LobeValues<double>& f) {
  return f[m::Lobe::SpecularReflection].r;
}

// ∫ f_spec(wi, wo) |wo_z| over the upper hemisphere by quadrature in a frame around the tangent
// t: a fibre reflects onto the cone wo·t = −wi·t, so z = wo·t is split around that value and the
// band of ±0.05 is cut into pieces narrower than the lobe.
double quadrature(const m::ClothBsdf<double>& bsdf, const Vec3d& wi, double roughness) {
  const test::SphereFrame frame = test::SphereFrame::around({1, 0, 0});
  auto f = [&](const Vec3d& wo) {
    return wo.z > 0 ? specular_reflection(bsdf.eval(wi, wo, 1.0)) * wo.z : 0.0;
  };
  auto over_phi = [&](double z) {
    auto g = [&](double phi) { return f(frame.direction(z, phi)); };
    return test::composite_adaptive_simpson(g, 0.0, 2 * M_PI, 64, 1e-9, 16);
  };
  const double z0 = -wi.x, band = 0.05;
  const double lo = std::max(-1.0, z0 - band), hi = std::min(1.0, z0 + band);
  const int band_pieces = int(std::ceil((hi - lo) / (roughness / 4)));
  double sum =
      test::composite_adaptive_simpson(over_phi, lo, hi, std::min(band_pieces, 4000), 1e-8, 8);
  if (lo > -1.0) sum += test::composite_adaptive_simpson(over_phi, -1.0, lo, 16, 1e-8, 10);
  if (hi < 1.0) sum += test::composite_adaptive_simpson(over_phi, hi, 1.0, 16, 1e-8, 10);
  return sum;
}

void expect_agrees_with_quadrature(double roughness, const Vec3d& wi) {
  const m::ClothBsdf<double> bsdf = specular_only(roughness);
  const double reference = quadrature(bsdf, wi, roughness);
  const m::LobeIntegral estimate = m::lobe_integral_cos(
      bsdf, wi, 1.0, [](const m::LobeValues<double>& f) { return f[m::Lobe::SpecularReflection]; },
      /*upper=*/true, 1u << 18, /*seed=*/7);
  ASSERT_GT(reference, 0.01);
  ASSERT_GT(estimate.standard_error.r, 0.0);
  // Unbiased: within 4 standard errors (plus the quadrature's own 1e-4 relative tolerance), and
  // the error bar is honest (not larger than 1 % of the value at 2^18 samples).
  EXPECT_NEAR(estimate.mean.r, reference, 4 * estimate.standard_error.r + 1e-4 * reference)
      << "roughness " << roughness;
  EXPECT_LT(estimate.standard_error.r, 0.01 * reference);
  EXPECT_EQ(estimate.samples, 1u << 18);
}

TEST(LobeIntegral, AgreesWithQuadratureAtModerateRoughness) {
  expect_agrees_with_quadrature(0.3, m::normalize(Vec3d{0.6, 0.0, 0.8}));
}

TEST(LobeIntegral, AgreesWithQuadratureForANarrowLobeAtGrazingIncidence) {
  expect_agrees_with_quadrature(1e-3, m::normalize(Vec3d{0.999, 0.0, 0.0447}));
}

// The pixel sum the slice image gives is what the estimator replaces: at roughness 1e-3 the
// midpoint rule over a 256² equal-area grid misses a large part of the lobe.
TEST(LobeIntegral, ThePixelSumIsUnderResolvedWhereTheEstimatorIsNot) {
  const Vec3d wi = m::normalize(Vec3d{0.999, 0.0, 0.0447});
  const m::ClothBsdf<double> bsdf = specular_only(1e-3);
  const int n = 256;
  m::DirectionGrid<double> grid{n, 0.0};
  double pixel_sum = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Vec3d wo = grid.direction((x + 0.5) / n, (y + 0.5) / n);
      pixel_sum += specular_reflection(bsdf.eval(wi, wo, 1.0)) * wo.z * grid.bin_solid_angle();
    }
  const double reference = quadrature(bsdf, wi, 1e-3);
  EXPECT_GT(std::abs(pixel_sum - reference), 0.05 * reference);
}

TEST(LobeIntegral, SameSeedSameResult) {
  const m::ClothBsdf<double> bsdf = specular_only(0.1);
  auto select = [](const m::LobeValues<double>& f) { return f.total; };
  const Vec3d wi = m::normalize(Vec3d{0.3, 0.2, 0.9});
  const m::LobeIntegral a = m::lobe_integral_cos(bsdf, wi, 1.0, select, true, 4096, 3);
  const m::LobeIntegral b = m::lobe_integral_cos(bsdf, wi, 1.0, select, true, 4096, 3);
  EXPECT_EQ(a.mean.r, b.mean.r);
  EXPECT_EQ(a.standard_error.g, b.standard_error.g);
}

}  // namespace

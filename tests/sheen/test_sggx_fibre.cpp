// The fibre-like SGGX distribution of the sheen layer (sheen/sggx_fibre.hpp): normalisation
// of D and of the phase function by quadrature, and its samplers against the closed forms by
// chi-square.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "sheen/rng.hpp"
#include "sheen/sggx_fibre.hpp"
#include "sheen_test_util.hpp"

using namespace clothbake::sheen;
using clothbake::sheen_test::chi_square_sphere;
using clothbake::sheen_test::integrate_sphere;

namespace {

Vec3d from_angles(double cos_theta, double phi) {
  const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

class SggxFibreTest : public ::testing::TestWithParam<double> {};

// integral <w, m>+ D(m) dm = sigma(w) = sqrt(w^T S w) (Heitz et al. 2015, Eq. 2 and 5).
TEST_P(SggxFibreTest, ProjectedAreaIsTheIntegralOfTheNdf) {
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(GetParam());
  for (double mu : {0.05, 0.4, 0.9}) {
    const Vec3d w = from_angles(mu, 0.7);
    const double integral = integrate_sphere(
        [&](const Vec3d& m) { return std::max(0.0, clothbake::model::dot(w, m)) * flakes.ndf(m); },
        2000, 64);
    EXPECT_NEAR(integral, flakes.projected_area(w), 2e-3 * flakes.projected_area(w)) << "mu " << mu;
  }
}

TEST_P(SggxFibreTest, PhaseFunctionIntegratesToOne) {
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(GetParam());
  for (double mu : {-0.8, 0.1, 0.6}) {
    const Vec3d wi = from_angles(mu, 2.0);
    const double integral =
        integrate_sphere([&](const Vec3d& wo) { return flakes.phase(wi, wo); }, 2000, 128);
    EXPECT_NEAR(integral, 1.0, 3e-3) << "mu " << mu;
  }
}

// The geometric visible-normal sampler against <wi, m>+ D(m) / sigma(wi).
TEST_P(SggxFibreTest, VisibleNormalSamplesMatchTheVisibleNdf) {
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(GetParam());
  Rng rng(3, 0);
  for (double mu : {0.15, 0.7}) {
    const Vec3d wi = from_angles(mu, 0.3);
    const auto result = chi_square_sphere(
        [&] { return flakes.sample_visible_normal(wi, rng.uniform(), rng.uniform()); },
        [&](const Vec3d& m) { return flakes.visible_ndf(wi, m); }, 400000);
    EXPECT_TRUE(result.passed) << result.message << " (mu " << mu << ")";
  }
}

TEST_P(SggxFibreTest, PhaseSamplesMatchThePhaseFunction) {
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(GetParam());
  Rng rng(4, 0);
  for (double mu : {-0.5, 0.2}) {
    const Vec3d wi = from_angles(mu, -1.0);
    const auto result =
        chi_square_sphere([&] { return flakes.sample_phase(wi, rng.uniform(), rng.uniform()); },
                          [&](const Vec3d& wo) { return flakes.phase(wi, wo); }, 400000);
    EXPECT_TRUE(result.passed) << result.message << " (mu " << mu << ")";
  }
}

INSTANTIATE_TEST_SUITE_P(Roughness, SggxFibreTest, ::testing::Values(1.0, 0.7, 0.45));

// sigma = 1 is a sphere of flakes: constant D = 1 / pi, unit projected area, isotropic phase.
TEST(SggxFibre, RoughnessOneIsIsotropic) {
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(1.0);
  const Vec3d a = from_angles(0.3, 1.0), b = from_angles(-0.9, 4.0);
  EXPECT_NEAR(flakes.ndf(a), 1.0 / kPi, 1e-15);
  EXPECT_NEAR(flakes.projected_area(b), 1.0, 1e-15);
  EXPECT_NEAR(flakes.phase(a, b), 1.0 / (4.0 * kPi), 1e-15);
}

// Roughness 0: the flakes are the walls of vertical needles, all normals horizontal, so specular
// scattering keeps the vertical component of a direction (the reason R = 0 at roughness 0).
TEST(SggxFibre, RoughnessZeroNormalsAreHorizontal) {
  const VerticalFibreSggx flakes = VerticalFibreSggx::from_roughness(0.0);
  Rng rng(5, 0);
  for (int k = 0; k < 1000; ++k) {
    const Vec3d wi = from_angles(2.0 * rng.uniform() - 1.0, 2.0 * kPi * rng.uniform());
    if (std::abs(wi.z) > 0.999) continue;
    const Vec3d m = flakes.sample_visible_normal(wi, rng.uniform(), rng.uniform());
    EXPECT_EQ(m.z, 0.0);
    EXPECT_GE(clothbake::model::dot(m, wi), -1e-12);
    // wi points back along the path, so the propagation direction before scattering is -wi.
    const Vec3d wo = flakes.sample_phase(wi, rng.uniform(), rng.uniform());
    EXPECT_NEAR(wo.z, -wi.z, 1e-12);
  }
  EXPECT_EQ(flakes.projected_area(Vec3d{0, 0, 1}), 0.0);
}

}  // namespace

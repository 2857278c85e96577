// The ASG model (model/asg.hpp) and the per-texel ASG fit (raycast/asg_fit.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "model/asg.hpp"
#include "model/directions.hpp"
#include "raycast/asg_fit.hpp"

using clothbake::model::Asg;
using clothbake::model::AsgParams;
using clothbake::model::AsgRecord;
using clothbake::model::DirectionGrid;
using clothbake::model::Vec3d;
namespace model = clothbake::model;
namespace raycast = clothbake::raycast;

namespace {

Vec3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    Vec3d v{g(rng), g(rng), g(rng)};
    double len = model::length(v);
    if (len > 1e-6) return v / len;
  }
}

AsgParams<double> random_params(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0, 1);
  AsgParams<double> p;
  Vec3d a = random_unit(rng);
  p.axis = {a.x, a.y, std::abs(a.z)};
  p.rotation = uni(rng) * 2 * M_PI;
  // Log-uniform bandwidths over [1e-2, 4096] plus exact zeros now and then.
  p.lambda = uni(rng) < 0.1 ? 0.0 : std::exp(std::log(1e-2) + uni(rng) * std::log(4096 / 1e-2));
  p.mu = uni(rng) < 0.1 ? 0.0 : std::exp(std::log(1e-2) + uni(rng) * std::log(4096 / 1e-2));
  p.amplitude = uni(rng) * 2;
  return p;
}

// Composite Simpson rule in the polar variable t = cos(theta), for asg_polar_integral.
double polar_quadrature(double k) {
  const int steps = 2000000;  // even
  const double h = 1.0 / steps;
  double sum = std::exp(-k) + 1.0;
  for (int i = 1; i < steps; ++i) {
    double t = i * h;
    sum += (i % 2 ? 4.0 : 2.0) * std::exp(-k * (1 - t * t));
  }
  return sum * h / 3;
}

// Midpoint rule over the hemisphere about the lobe's axis on an n x n equal-area grid (every cell
// has solid angle 2 pi / n^2); the lobe vanishes on the other hemisphere.
double sphere_quadrature(const Asg<double>& g, int n) {
  DirectionGrid<double> grid{n, 0.0};
  double sum = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      Vec3d l = grid.bin_center(i, j);
      Vec3d v = g.x * l.x + g.y * l.y + g.z * l.z;
      sum += model::asg_eval(g, v);
    }
  return sum * grid.bin_solid_angle();
}

}  // namespace

TEST(AsgModel, EvaluatesTheDefinition) {
  AsgParams<double> p;
  p.axis = model::normalize(Vec3d{0.3, -0.2, 1.0});
  p.rotation = 0.7;
  p.lambda = 5;
  p.mu = 2;
  p.amplitude = 0.8;
  Asg<double> g = model::asg_from_params(p);
  EXPECT_NEAR(model::dot(g.x, g.y), 0, 1e-15);
  EXPECT_NEAR(model::dot(g.x, g.z), 0, 1e-15);
  EXPECT_NEAR(model::length(model::cross(g.x, g.y) - g.z), 0, 1e-15);  // right-handed
  EXPECT_DOUBLE_EQ(model::asg_eval(g, g.z), 0.8);
  // Along x at angle theta from the axis: c exp(-lambda sin^2 theta); along y with mu.
  for (double theta : {0.1, 0.5, 1.2, 1.5}) {
    Vec3d vx = g.z * std::cos(theta) + g.x * std::sin(theta);
    Vec3d vy = g.z * std::cos(theta) + g.y * std::sin(theta);
    EXPECT_NEAR(model::asg_eval(g, vx), 0.8 * std::exp(-5 * std::pow(std::sin(theta), 2)), 1e-14);
    EXPECT_NEAR(model::asg_eval(g, vy), 0.8 * std::exp(-2 * std::pow(std::sin(theta), 2)), 1e-14);
  }
  // Zero on and behind the plane of the axis.
  EXPECT_EQ(model::asg_eval(g, g.x), 0.0);
  EXPECT_EQ(model::asg_eval(g, -g.z), 0.0);
}

TEST(AsgModel, ZeroBandwidthIsAConstantHemisphere) {
  // The reason for the indicator instead of Xu et al.'s smooth term: V = 1 is representable.
  AsgParams<double> p;
  p.amplitude = 1;
  Asg<double> g = model::asg_from_params(p);
  std::mt19937_64 rng(3);
  for (int k = 0; k < 1000; ++k) {
    Vec3d v = random_unit(rng);
    EXPECT_EQ(model::asg_eval(g, v), v.z > 0 ? 1.0 : 0.0);
  }
}

TEST(AsgModel, CanonicalParametersDescribeTheSameLobe) {
  std::mt19937_64 rng(11);
  for (int k = 0; k < 500; ++k) {
    AsgParams<double> p = random_params(rng);
    Asg<double> g = model::asg_from_params(p);
    AsgParams<double> c = model::asg_to_params(g);
    EXPECT_GE(c.lambda, c.mu);
    EXPECT_GE(c.rotation, 0.0);
    EXPECT_LT(c.rotation, M_PI);
    Asg<double> h = model::asg_from_params(c);
    for (int s = 0; s < 20; ++s) {
      Vec3d v = random_unit(rng);
      double a = model::asg_eval(g, v), b = model::asg_eval(h, v);
      ASSERT_NEAR(a, b, 1e-9 * (1 + a)) << "lobe " << k;
    }
  }
}

TEST(AsgModel, PolarIntegralMatchesQuadrature) {
  for (double k : {0.0, 1e-3, 0.5, 1.0, 7.0, 39.999, 40.0, 40.001, 100.0, 1000.0, 4096.0}) {
    double expected = polar_quadrature(k);
    EXPECT_NEAR(model::asg_polar_integral(k), expected, 1e-9 * expected) << "k = " << k;
  }
  // Closed forms: g(0) = 1; large k: 1/(2k) (1 + 1/(2k) + 3/(4k^2) + ...).
  EXPECT_EQ(model::asg_polar_integral(0.0), 1.0);
  double k = 1e6;
  EXPECT_NEAR(model::asg_polar_integral(k), 1 / (2 * k) * (1 + 1 / (2 * k)), 1e-18);
}

TEST(AsgModel, IntegralMatchesSphereQuadrature) {
  std::mt19937_64 rng(5);
  struct Case {
    double lambda, mu;
  };
  std::vector<Case> cases = {{0, 0},     {0.5, 0.5}, {3, 0},    {30, 2},
                             {200, 200}, {4096, 0},  {4096, 1}, {1000, 999}};
  for (const Case& c : cases) {
    AsgParams<double> p;
    p.axis = model::normalize(Vec3d{0.2, 0.1, 1});
    p.rotation = 0.4;
    p.lambda = c.lambda;
    p.mu = c.mu;
    p.amplitude = 1.3;
    Asg<double> g = model::asg_from_params(p);
    double exact = model::asg_integral(g);
    // The midpoint rule's error falls as 1/n^2: Richardson extrapolation of n = 512 and 1024.
    double quad = (4 * sphere_quadrature(g, 1024) - sphere_quadrature(g, 512)) / 3;
    EXPECT_NEAR(exact, quad, 2e-5 * quad) << "lambda " << c.lambda << " mu " << c.mu;
  }
  // Zero bandwidths: 2 pi c exactly.
  AsgParams<double> flat;
  flat.amplitude = 0.5;
  EXPECT_NEAR(model::asg_integral(model::asg_from_params(flat)), M_PI, 1e-12);
}

TEST(AsgModel, SharpLobesApproachXusClosedForm) {
  for (double lambda : {20.0, 100.0, 1000.0}) {
    for (double ratio : {1.0, 3.0}) {
      AsgParams<double> p;
      p.lambda = lambda * ratio;
      p.mu = lambda;
      p.amplitude = 1;
      Asg<double> g = model::asg_from_params(p);
      double exact = model::asg_integral(g), sharp = model::asg_integral_sharp(g);
      // The relative correction is about 1/(2 mu) + 1/(2 lambda) (next term of the series).
      EXPECT_NEAR(sharp / exact, 1.0, 1.5 / lambda) << lambda << " x " << ratio;
      EXPECT_LT(sharp, exact);
    }
  }
}

TEST(AsgModel, PackingErrorIsBounded) {
  std::mt19937_64 rng(17);
  double worst = 0;
  for (int k = 0; k < 3000; ++k) {
    AsgParams<double> p = random_params(rng);
    Asg<double> g = model::asg_from_params(p);
    Asg<double> h = model::asg_from_params(model::unpack_asg<double>(model::pack_asg(p)));
    for (int s = 0; s < 50; ++s) {
      Vec3d v = random_unit(rng);
      // Directions within 1e-3 of the lobe's cut plane are excluded: the axis moves by ~5e-5 rad.
      if (std::abs(model::dot(v, g.z)) < 1e-3) continue;
      worst = std::max(worst, std::abs(model::asg_eval(g, v) - model::asg_eval(h, v)));
    }
  }
  EXPECT_LT(worst, 3e-3);
  std::printf("max |G - G_packed| over 150k samples: %.2e\n", worst);
}

TEST(AsgModel, AnyRecordUnpacksToABoundedLobe) {
  std::mt19937_64 rng(23);
  for (int k = 0; k < 100000; ++k) {
    uint64_t bits = rng();
    AsgRecord r;
    r.axis_u = uint16_t(bits), r.axis_v = uint16_t(bits >> 16), r.rotation = uint16_t(bits >> 32);
    r.lambda = uint16_t(bits >> 48), r.mu = uint16_t(rng()), r.amplitude = uint16_t(rng());
    AsgParams<double> p = model::unpack_asg<double>(r);
    ASSERT_TRUE(std::isfinite(p.lambda) && p.lambda >= 0 && p.lambda <= model::kAsgMaxBandwidth);
    ASSERT_TRUE(std::isfinite(p.mu) && p.mu >= 0 && p.mu <= model::kAsgMaxBandwidth);
    ASSERT_TRUE(p.amplitude >= 0 && p.amplitude <= model::kAsgMaxAmplitude);
    ASSERT_NEAR(model::length(p.axis), 1.0, 1e-12);
    ASSERT_GE(p.axis.z, 0.0);
  }
  // The extremes decode to the documented ranges.
  AsgRecord top;
  top.lambda = top.mu = top.amplitude = 65535;
  AsgParams<double> p = model::unpack_asg<double>(top);
  EXPECT_EQ(p.lambda, model::kAsgMaxBandwidth);
  EXPECT_EQ(p.amplitude, model::kAsgMaxAmplitude);
}

// ---- The fit ----------------------------------------------------------------------------------

namespace {

raycast::FitDirections hemisphere_directions(int n) {
  DirectionGrid<double> grid{n, 0.0};
  raycast::FitDirections d;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      Vec3d v = grid.bin_center(i, j);
      d.push_back(v.x, v.y, v.z);
    }
  return d;
}

template <class Predicate>
std::vector<uint8_t> sample(const raycast::FitDirections& d, Predicate visible) {
  std::vector<uint8_t> v(d.size());
  for (std::size_t k = 0; k < d.size(); ++k)
    v[k] = visible(Vec3d{d.x[k], d.y[k], d.z[k]}) ? 1 : 0;
  return v;
}

}  // namespace

TEST(AsgFit, AllOrNothingGetTheExactFallback) {
  auto d = hemisphere_directions(32);
  auto all = sample(d, [](const Vec3d&) { return true; });
  auto none = sample(d, [](const Vec3d&) { return false; });
  auto a = raycast::fit_asg(d, all.data());
  EXPECT_EQ(a.params.amplitude, 1.0);
  EXPECT_EQ(a.params.lambda, 0.0);
  EXPECT_EQ(a.params.mu, 0.0);
  EXPECT_EQ(a.rms_error, 0.0);
  EXPECT_EQ(raycast::asg_rms_error(d, all.data(), a.params), 0.0);
  auto b = raycast::fit_asg(d, none.data());
  EXPECT_EQ(b.params.amplitude, 0.0);
  EXPECT_EQ(b.rms_error, 0.0);
}

TEST(AsgFit, RecoversAValleyBand) {
  // Visible within 17 degrees of the plane x = 0: a valley running along y.
  auto d = hemisphere_directions(32);
  auto v = sample(d, [](const Vec3d& w) { return std::abs(w.x) < 0.3; });
  auto fit = raycast::fit_asg(d, v.data());
  Asg<double> g = model::asg_from_params(fit.params);
  EXPECT_GT(std::abs(g.x.x), 0.95) << "the sharp axis should be across the valley";
  EXPECT_GT(fit.params.lambda, 5.0);
  EXPECT_LT(fit.params.mu, 1.0);
  EXPECT_GT(g.z.z, 0.95);
  EXPECT_LT(fit.rms_error, 0.3);
  EXPECT_NEAR(fit.rms_error, raycast::asg_rms_error(d, v.data(), fit.params), 1e-12);
  EXPECT_LE(fit.evaluations, raycast::kAsgFitMaxEvaluations);
}

TEST(AsgFit, RecoversATiltedHalfSpace) {
  // A texel on a facet tilted 40 degrees towards +x sees the half-space above the facet.
  auto d = hemisphere_directions(32);
  const double tilt = 40 * M_PI / 180;
  Vec3d n{std::sin(tilt), 0, std::cos(tilt)};
  auto v = sample(d, [&](const Vec3d& w) { return model::dot(w, n) > 0; });
  auto fit = raycast::fit_asg(d, v.data());
  EXPECT_LT(fit.rms_error, 0.12);
  EXPECT_GT(model::dot(fit.params.axis, n), 0.97);
}

TEST(AsgFit, FitsAConeOfSky) {
  // Visible within 35 degrees of a direction 20 degrees off the zenith (a pit between yarns).
  auto d = hemisphere_directions(32);
  Vec3d c = model::normalize(Vec3d{0.0, std::sin(0.35), std::cos(0.35)});
  auto v = sample(d, [&](const Vec3d& w) { return model::dot(w, c) > std::cos(35 * M_PI / 180); });
  auto fit = raycast::fit_asg(d, v.data());
  EXPECT_GT(model::dot(fit.params.axis, c), 0.99);
  EXPECT_LT(fit.rms_error, 0.2);
  EXPECT_NEAR(fit.params.lambda, fit.params.mu, 0.3 * fit.params.lambda);  // isotropic-ish
}

TEST(AsgFit, IsBoundedAndDeterministicOnNoise) {
  auto d = hemisphere_directions(16);
  std::mt19937_64 rng(99);
  for (int k = 0; k < 200; ++k) {
    double p = (k % 10 + 0.5) / 10;
    std::vector<uint8_t> v(d.size());
    for (auto& b : v)
      b = std::uniform_real_distribution<double>(0, 1)(rng) < p;
    auto a = raycast::fit_asg(d, v.data());
    auto b = raycast::fit_asg(d, v.data());
    ASSERT_EQ(std::memcmp(&a.params, &b.params, sizeof a.params), 0);
    ASSERT_TRUE(std::isfinite(a.rms_error));
    ASSERT_LE(a.rms_error, 1.0);
    ASSERT_GE(a.params.lambda, 0);
    ASSERT_LE(a.params.lambda, model::kAsgMaxBandwidth);
    ASSERT_GE(a.params.mu, 0);
    ASSERT_LE(a.params.amplitude, model::kAsgMaxAmplitude);
    ASSERT_GE(a.params.axis.z, 0);
    ASSERT_LE(a.evaluations, raycast::kAsgFitMaxEvaluations);
    // Never worse than the best flat lobe, sqrt(p (1 - p)) for a visible fraction p.
    double frac = 0;
    for (auto bit : v)
      frac += bit;
    frac /= double(v.size());
    ASSERT_LE(a.rms_error, std::sqrt(frac * (1 - frac)) + 1e-12);
  }
}

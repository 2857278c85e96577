// Visibility clusters (cluster/visibility_clusters.hpp): bin averages against fine quadrature,
// mean visibility and explained variance against brute-force recomputation, exact cases.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>
#include <vector>

#include "cluster/visibility_clusters.hpp"
#include "common/error.hpp"
#include "model/directions.hpp"

using namespace clothbake;
using namespace clothbake::cluster;
using model::AsgParams;
using model::Vec3d;
using model::Vec3f;

namespace {

AsgParams<float> open_sky() {
  return {Vec3f(0, 0, 1), 0.0f, 0.0f, 0.0f, 1.0f};
}

// Random plausible lobes of `types` kinds, with noise, for an N x N map.
std::vector<AsgParams<float>> random_lobes(int n, int types, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<AsgParams<float>> base;
  for (int t = 0; t < types; ++t)
    base.push_back({model::normalize(Vec3f(u(rng) - 0.5f, u(rng) - 0.5f, 1.0f)), 3.0f * u(rng),
                    40.0f * u(rng), 4.0f * u(rng), 0.5f + 0.5f * u(rng)});
  std::vector<AsgParams<float>> out;
  for (int i = 0; i < n * n; ++i) {
    AsgParams<float> p = base[std::size_t(rng() % uint64_t(types))];
    p.lambda *= 1.0f + 0.2f * (u(rng) - 0.5f);
    p.amplitude = std::min(1.0f, p.amplitude * (1.0f + 0.1f * (u(rng) - 0.5f)));
    out.push_back(p);
  }
  return out;
}

}  // namespace

TEST(VisibilityClusters, BinAveragesMatchFineQuadrature) {
  const int dirs = 8;
  BinDirections coarse = hemisphere_bin_directions(dirs, 4);
  BinDirections fine = hemisphere_bin_directions(dirs, 64);
  model::Asg<float> g = model::asg_from_params(
      AsgParams<float>{model::normalize(Vec3f(0.3f, 0.1f, 1.0f)), 0.4f, 30.0f, 3.0f, 0.9f});
  std::vector<float> a(dirs * dirs), b(dirs * dirs);
  asg_bin_averages(g, coarse, a.data());
  asg_bin_averages(g, fine, b.data());
  // A fine midpoint rule converges to the bin average; 4x4 is within a few percent of the peak.
  for (int k = 0; k < dirs * dirs; ++k)
    EXPECT_NEAR(a[std::size_t(k)], b[std::size_t(k)], 0.03) << k;
  // Sum of bin averages times the bin solid angle is the integral over the hemisphere; the ASG
  // with its axis inside the hemisphere and [v.z > 0] cut is compared with a direct quadrature.
  double integral = 0;
  for (float v : b)
    integral += v;
  integral *= 2 * M_PI / (dirs * dirs);
  // Direct: the same hemisphere integral by a 2000 x 2000 midpoint rule in (cos theta, phi).
  double direct = 0;
  const int m = 2000;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      double ct = (i + 0.5) / m, phi = 2 * M_PI * (j + 0.5) / m, st = std::sqrt(1 - ct * ct);
      Vec3f d(float(st * std::cos(phi)), float(st * std::sin(phi)), float(ct));
      direct += model::asg_eval(g, d);
    }
  direct *= 2 * M_PI / (double(m) * m);
  EXPECT_NEAR(integral, direct, 2e-3 * direct);
}

TEST(VisibilityClusters, OpenSkyIsExactlyOneEverywhere) {
  std::vector<AsgParams<float>> lobes(16 * 16, open_sky());
  VisibilityClusterOptions o;
  o.clusters = 8;
  VisibilityClusters r = cluster_visibility(16, lobes, o);
  ASSERT_EQ(r.clusters, 1);  // one distinct lobe
  for (float v : r.mean_visibility)
    EXPECT_FLOAT_EQ(v, 1.0f);
  EXPECT_EQ(r.variance, 0.0);
  EXPECT_EQ(r.explained_fraction, 1.0);
}

TEST(VisibilityClusters, MeansAndVarianceMatchBruteForce) {
  const int n = 24;
  auto lobes = random_lobes(n, 5, 7);
  VisibilityClusterOptions o;
  o.clusters = 3;  // fewer clusters than types: a genuine residual
  o.visibility_dirs = 8;
  o.samples_per_bin_side = 2;
  VisibilityClusters r = cluster_visibility(n, lobes, o);
  ASSERT_EQ(r.clusters, 3);
  const int bins = 64;
  BinDirections dirs = hemisphere_bin_directions(8, 2);
  std::vector<std::vector<float>> v(lobes.size(), std::vector<float>(bins));
  for (std::size_t x = 0; x < lobes.size(); ++x)
    asg_bin_averages(model::asg_from_params(lobes[x]), dirs, v[x].data());
  std::vector<double> global(bins, 0.0), mean(3 * bins, 0.0);
  std::vector<double> count(3, 0.0);
  for (std::size_t x = 0; x < lobes.size(); ++x) {
    count[r.labels[x]] += 1;
    for (int b = 0; b < bins; ++b) {
      global[std::size_t(b)] += v[x][std::size_t(b)] / double(lobes.size());
      mean[r.labels[x] * bins + std::size_t(b)] += v[x][std::size_t(b)];
    }
  }
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < bins; ++b) {
      double m = mean[std::size_t(c * bins + b)] / count[std::size_t(c)];
      EXPECT_NEAR(r.mean_visibility[std::size_t(c * bins + b)], m, 1e-6);
      mean[std::size_t(c * bins + b)] = m;
    }
  double var = 0, res = 0;
  std::vector<double> cvar(3, 0.0), cres(3, 0.0);
  for (std::size_t x = 0; x < lobes.size(); ++x)
    for (int b = 0; b < bins; ++b) {
      double dv = v[x][std::size_t(b)] - global[std::size_t(b)];
      double dr = v[x][std::size_t(b)] - mean[r.labels[x] * bins + std::size_t(b)];
      var += dv * dv;
      res += dr * dr;
      cvar[r.labels[x]] += dv * dv;
      cres[r.labels[x]] += dr * dr;
    }
  EXPECT_NEAR(r.explained_fraction, 1 - res / var, 1e-6);
  EXPECT_NEAR(r.variance, var / (double(lobes.size()) * bins), 1e-7);
  EXPECT_GT(r.explained_fraction, 0.3);
  EXPECT_LT(r.explained_fraction, 1.0);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(r.stats[std::size_t(c)].explained_fraction,
                1 - cres[std::size_t(c)] / cvar[std::size_t(c)], 1e-6);
    EXPECT_EQ(r.stats[std::size_t(c)].texels, uint64_t(count[std::size_t(c)]));
  }
}

TEST(VisibilityClusters, OneClusterExplainsNothingAndOnePerTypeExplainsAll) {
  const int n = 16;
  auto lobes = random_lobes(n, 4, 3);
  for (auto& p : lobes)
    p.amplitude = 1.0f, p.lambda = std::round(p.lambda);  // exact types
  std::vector<AsgParams<float>> exact;
  // Four exact types (no noise) in a checker of 4 x 4 blocks.
  auto base = random_lobes(1, 1, 1)[0];
  for (int i = 0; i < n * n; ++i) {
    AsgParams<float> p = base;
    p.axis =
        model::normalize(Vec3f(0.4f * float((i % n) / 4 % 2), 0.4f * float((i / n) / 4 % 2), 1.0f));
    exact.push_back(p);
  }
  VisibilityClusterOptions o;
  o.visibility_dirs = 8;
  o.clusters = 1;
  VisibilityClusters one = cluster_visibility(n, exact, o);
  EXPECT_NEAR(one.explained_fraction, 0.0, 1e-9);
  o.clusters = 4;
  VisibilityClusters four = cluster_visibility(n, exact, o);
  EXPECT_EQ(four.clusters, 4);
  EXPECT_NEAR(four.explained_fraction, 1.0, 1e-9);
}

TEST(VisibilityClusters, DeterministicForAnyThreadCount) {
  auto lobes = random_lobes(32, 6, 9);
  VisibilityClusterOptions o;
  o.visibility_dirs = 16;
  VisibilityClusters a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = cluster_visibility(32, lobes, o);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = cluster_visibility(32, lobes, o);
  }
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.mean_visibility, b.mean_visibility);
  EXPECT_EQ(a.explained_fraction, b.explained_fraction);
}

TEST(VisibilityClusters, RejectsBadInput) {
  std::vector<AsgParams<float>> lobes(15, open_sky());
  VisibilityClusterOptions o;
  EXPECT_THROW(cluster_visibility(4, lobes, o), Error);  // 15 != 16
  lobes.push_back(open_sky());
  o.clusters = 300;
  EXPECT_THROW(cluster_visibility(4, lobes, o), Error);
  o.clusters = 2;
  lobes[5].lambda = NAN;
  try {
    cluster_visibility(4, lobes, o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("texel 5"), std::string::npos) << e.what();
  }
}

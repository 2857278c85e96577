// The ASG embedding (cluster/asg_embedding.hpp): symmetric-equivalent lobes embed to the same
// point and land in the same cluster; distances have the documented closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "cluster/asg_embedding.hpp"
#include "cluster/kmeans.hpp"

using namespace clothbake;
using namespace clothbake::cluster;
using model::AsgParams;
using model::Vec3d;

namespace {

std::vector<float> embed(const AsgParams<double>& p, const AsgEmbeddingWeights& w = {}) {
  std::vector<float> e(kAsgEmbeddingDim);
  embed_asg(p, w, e.data());
  return e;
}

double distance(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return std::sqrt(s);
}

// An embedding from an explicit frame (x, y, z), bypassing the rotation parameter.
std::vector<float> embed_frame(const Vec3d& x, const Vec3d& y, const Vec3d& z, double lambda,
                               double mu, double c) {
  model::Asg<double> g;
  g.x = x;
  g.y = y;
  g.z = z;
  g.lambda = lambda;
  g.mu = mu;
  g.amplitude = c;
  return embed(model::asg_to_params(g));
}

}  // namespace

TEST(AsgEmbedding, SymmetricEquivalentLobesEmbedIdentically) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Vec3d axis = model::normalize(Vec3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) + 0.05));
    double psi = u(rng) * 2 * M_PI, lambda = 4000 * u(rng) * u(rng), mu = 50 * u(rng), c = u(rng);
    auto e = embed({axis, psi, lambda, mu, c});
    // psi is pi-periodic.
    EXPECT_LT(distance(e, embed({axis, psi + M_PI, lambda, mu, c})), 2e-5);
    EXPECT_LT(distance(e, embed({axis, psi - 3 * M_PI, lambda, mu, c})), 2e-5);
    // Swapping the bandwidths is a quarter turn.
    EXPECT_LT(distance(e, embed({axis, psi + M_PI / 2, mu, lambda, c})), 2e-5);
    // Sign flips of the tangent axes, from the explicit frame (not through psi).
    model::Asg<double> g = model::asg_from_params(AsgParams<double>{axis, psi, lambda, mu, c});
    EXPECT_LT(distance(e, embed_frame(-g.x, -g.y, g.z, lambda, mu, c)), 2e-5);
    EXPECT_LT(distance(e, embed_frame(g.y, -g.x, g.z, mu, lambda, c)), 2e-5);
    // An isotropic lobe does not depend on the rotation at all.
    auto iso = embed({axis, psi, lambda, lambda, c});
    EXPECT_LT(distance(iso, embed({axis, psi + 1.234, lambda, lambda, c})), 2e-5);
  }
}

TEST(AsgEmbedding, DistancesFollowTheClosedForms) {
  AsgEmbeddingWeights w;
  const Vec3d z(0, 0, 1);
  // Same orientation: w_bw * |(l1, l2) - (l1', l2')|.
  auto a = embed({z, 0.3, 10.0, 2.0, 1.0}, w);
  auto b = embed({z, 0.3, 100.0, 5.0, 1.0}, w);
  double dl1 = std::log1p(100.0) - std::log1p(10.0), dl2 = std::log1p(5.0) - std::log1p(2.0);
  EXPECT_NEAR(distance(a, b), w.bandwidth * std::hypot(dl1, dl2), 1e-5);
  // Rotation about a common axis: 4 w^2 a a (1 - cos 2 dpsi) added to the squared distance.
  for (double dpsi : {0.1, 0.5, M_PI / 4, M_PI / 2, 2.0}) {
    auto r = embed({z, 0.3 + dpsi, 10.0, 2.0, 1.0}, w);
    double half = 0.5 * (std::log1p(10.0) - std::log1p(2.0));
    double expect =
        std::sqrt(4 * w.bandwidth * w.bandwidth * half * half * (1 - std::cos(2 * dpsi)));
    EXPECT_NEAR(distance(a, r), expect, 1e-5) << dpsi;
  }
  // Axis: chord distance times w_axis; amplitude: |dc| times w_amp (isotropic lobes).
  auto p = embed({z, 0, 3.0, 3.0, 1.0}, w);
  auto q = embed({Vec3d(std::sin(0.4), 0, std::cos(0.4)), 0, 3.0, 3.0, 1.0}, w);
  EXPECT_NEAR(distance(p, q), w.axis * 2 * std::sin(0.2), 1e-6);
  auto s = embed({z, 0, 3.0, 3.0, 0.25}, w);
  EXPECT_NEAR(distance(p, s), w.amplitude * 0.75, 1e-6);
}

TEST(AsgEmbedding, SymmetricVariantsLandInTheSameCluster) {
  // Four visibility types; every lobe is written in one of its equivalent parameterisations at
  // random (psi + k pi, swapped bandwidths with psi + pi/2) plus small noise. K-means on the
  // embedding must recover the four types exactly.
  struct Type {
    Vec3d axis;
    double psi, lambda, mu, c;
  };
  std::vector<Type> types = {{model::normalize(Vec3d(0.3, 0.0, 1.0)), 0.2, 40, 2, 1.0},
                             {model::normalize(Vec3d(-0.3, 0.0, 1.0)), 1.7, 40, 2, 1.0},
                             {Vec3d(0, 0, 1), 0.0, 0.5, 0.5, 1.0},
                             {model::normalize(Vec3d(0.0, 0.5, 1.0)), 0.9, 300, 30, 0.6}};
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<AsgParams<float>> lobes;
  std::vector<int> truth;
  for (int i = 0; i < 4000; ++i) {
    int t = int(rng() % 4);
    const Type& ty = types[std::size_t(t)];
    double psi = ty.psi + 0.02 * (u(rng) - 0.5) + M_PI * double(int(rng() % 5) - 2);
    double lambda = ty.lambda * (1 + 0.05 * (u(rng) - 0.5)),
           mu = ty.mu * (1 + 0.05 * (u(rng) - 0.5));
    if (rng() % 2) {
      std::swap(lambda, mu);
      psi += M_PI / 2;
    }
    lobes.push_back({model::Vec3f(ty.axis), float(psi), float(lambda), float(mu), float(ty.c)});
    truth.push_back(t);
  }
  std::vector<float> e = embed_asgs(lobes, AsgEmbeddingWeights{});
  KMeansOptions o;
  o.clusters = 4;
  KMeansResult r = kmeans({e.data(), lobes.size(), kAsgEmbeddingDim}, o);
  ASSERT_EQ(r.clusters, 4);
  std::vector<int> label_of_type(4, -1);
  for (std::size_t i = 0; i < lobes.size(); ++i) {
    int& l = label_of_type[std::size_t(truth[i])];
    if (l < 0) l = r.labels[i];
    ASSERT_EQ(l, r.labels[i]) << "lobe " << i << " of type " << truth[i];
  }
}

// Nelder-Mead (sheen/nelder_mead.hpp) on functions with known minima.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "sheen/nelder_mead.hpp"

using clothbake::sheen::nelder_mead;
using clothbake::sheen::NelderMeadOptions;

namespace {

TEST(NelderMead, FindsTheMinimumOfAQuadratic) {
  auto f = [](const std::vector<double>& x) {
    return 3.0 * (x[0] - 1.5) * (x[0] - 1.5) + (x[1] + 2.0) * (x[1] + 2.0) +
           0.5 * (x[0] - 1.5) * (x[1] + 2.0) + 7.0;
  };
  const auto r = nelder_mead(f, {0.0, 0.0}, {0.5, 0.5});
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.x[0], 1.5, 1e-5);
  EXPECT_NEAR(r.x[1], -2.0, 1e-5);
  EXPECT_NEAR(r.f, 7.0, 1e-10);
}

TEST(NelderMead, FollowsTheRosenbrockValley) {
  auto f = [](const std::vector<double>& x) {
    return 100.0 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1.0 - x[0], 2);
  };
  NelderMeadOptions options;
  options.max_evaluations = 5000;
  const auto r = nelder_mead(f, {-1.2, 1.0}, {0.1, 0.1}, options);
  EXPECT_NEAR(r.x[0], 1.0, 1e-4);
  EXPECT_NEAR(r.x[1], 1.0, 1e-4);
}

TEST(NelderMead, RespectsRejectedRegionsAndTheEvaluationBudget) {
  // Minimum of (x - 2)^2 restricted to x <= 1 (infinity outside) is at the boundary x = 1.
  auto f = [](const std::vector<double>& x) {
    return x[0] > 1.0 ? std::numeric_limits<double>::infinity() : (x[0] - 2.0) * (x[0] - 2.0);
  };
  const auto r = nelder_mead(f, {0.0}, {0.3});
  EXPECT_LE(r.x[0], 1.0);
  EXPECT_NEAR(r.x[0], 1.0, 1e-5);

  NelderMeadOptions few;
  few.max_evaluations = 10;
  const auto capped = nelder_mead(f, {-50.0}, {0.01}, few);
  EXPECT_FALSE(capped.converged);
  EXPECT_LE(capped.evaluations, 12);  // the last step may take two evaluations
}

TEST(NelderMead, RejectsMismatchedSizes) {
  auto f = [](const std::vector<double>& x) { return x[0]; };
  EXPECT_THROW(nelder_mead(f, {0.0, 1.0}, {0.1}), std::invalid_argument);
  EXPECT_THROW(nelder_mead(f, {}, {}), std::invalid_argument);
}

}  // namespace

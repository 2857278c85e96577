// Randomized truncated SVD (compress/randomized_svd.hpp): exact low-rank recovery against
// Eigen's dense SVD, orthonormality, rank clamping, degenerate data and thread determinism.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "compress/randomized_svd.hpp"

namespace clothbake::compress {
namespace {

// m x n row-major matrix of exact rank `rank` with singular values 2^-j (j < rank), plus noise.
std::vector<float> low_rank(std::size_t m, std::size_t n, int rank, double noise, uint64_t seed) {
  const Eigen::MatrixXd u =
      gaussian_matrix(m, std::size_t(rank), seed).householderQr().householderQ() *
      Eigen::MatrixXd::Identity(Eigen::Index(m), rank);
  const Eigen::MatrixXd v =
      gaussian_matrix(n, std::size_t(rank), seed + 1).householderQr().householderQ() *
      Eigen::MatrixXd::Identity(Eigen::Index(n), rank);
  Eigen::VectorXd s(rank);
  for (int j = 0; j < rank; ++j)
    s[j] = std::ldexp(100.0, -j);
  Eigen::MatrixXd a = u * s.asDiagonal() * v.transpose();
  a += noise * gaussian_matrix(m, n, seed + 2);
  std::vector<float> out(m * n);
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = 0; j < n; ++j)
      out[i * n + j] = float(a(Eigen::Index(i), Eigen::Index(j)));
  return out;
}

TEST(RandomizedSvd, RecoversSingularValuesOfALowRankMatrix) {
  const std::size_t m = 3000, n = 120;  // more than one row block
  const auto data = low_rank(m, n, 6, 0.0, 11);
  RowSubsetMatrix a{data.data(), m, n, {}, {}};
  RandomizedSvdOptions o;
  o.rank = 6;
  const TruncatedSvd svd = randomized_svd(a, o);
  ASSERT_EQ(svd.rank, 6);
  for (int j = 0; j < 6; ++j)
    EXPECT_NEAR(svd.singular[j], std::ldexp(100.0, -j), 1e-3) << j;
  const Eigen::MatrixXd gram = svd.basis.transpose() * svd.basis;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(6, 6)).cwiseAbs().maxCoeff(), 1e-10);
  // Projection residuals: the data lies in the basis' span.
  RowMatrixF coefficients;
  std::vector<double> residual(m);
  project_rows(a, svd.basis, &coefficients, residual);
  // Float data and float products: the residual is rounding, relative to the rows' energy.
  double worst = 0, energy = 0;
  for (double r : residual)
    worst = std::max(worst, r);
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = 0; j < n; ++j)
      energy = std::max(energy, double(data[i * n + j]) * data[i * n + j] * n);
  EXPECT_LT(worst, 1e-5 * energy);
}

TEST(RandomizedSvd, MatchesDenseSvdOnNoisyDataWithCentringAndSubset) {
  const std::size_t m = 1500, n = 64;
  const auto data = low_rank(m, n, 10, 0.05, 3);
  std::vector<uint32_t> rows;
  for (uint32_t i = 0; i < m; i += 3)
    rows.push_back(i);
  std::vector<float> mean(n, 0.0f);
  for (uint32_t r : rows)
    for (std::size_t j = 0; j < n; ++j)
      mean[j] += data[r * n + j] / float(rows.size());
  RowSubsetMatrix a{data.data(), m, n, rows, mean};
  RandomizedSvdOptions o;
  o.rank = 8;
  o.power_iterations = 3;
  const TruncatedSvd svd = randomized_svd(a, o);
  Eigen::MatrixXd dense(Eigen::Index(rows.size()), Eigen::Index(n));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < n; ++j)
      dense(Eigen::Index(i), Eigen::Index(j)) = double(data[rows[i] * n + j]) - mean[j];
  Eigen::JacobiSVD<Eigen::MatrixXd> reference(dense);
  for (int j = 0; j < 8; ++j)
    EXPECT_NEAR(svd.singular[j], reference.singularValues()[j],
                1e-3 * reference.singularValues()[0]);
  EXPECT_NEAR(svd.total_energy, dense.squaredNorm(), 1e-6 * dense.squaredNorm());
}

TEST(RandomizedSvd, RankAboveTheDataAndAllZeroData) {
  std::vector<float> zeros(50 * 7, 0.0f);
  RowSubsetMatrix a{zeros.data(), 50, 7, {}, {}};
  RandomizedSvdOptions o;
  o.rank = 20;  // larger than min(m, n) = 7
  const TruncatedSvd svd = randomized_svd(a, o);
  EXPECT_EQ(svd.rank, 7);
  EXPECT_TRUE(svd.basis.allFinite());
  EXPECT_TRUE(svd.singular.allFinite());
  EXPECT_EQ(svd.singular.maxCoeff(), 0.0);
  EXPECT_EQ(svd.total_energy, 0.0);
  std::vector<float> one_row = {1, 2, 3};
  RowSubsetMatrix b{one_row.data(), 1, 3, {}, {}};
  const TruncatedSvd s1 = randomized_svd(b, o);
  EXPECT_EQ(s1.rank, 1);
  EXPECT_NEAR(s1.singular[0], std::sqrt(14.0), 1e-5);
  RowSubsetMatrix empty{one_row.data(), 0, 3, {}, {}};
  EXPECT_EQ(randomized_svd(empty, o).rank, 0);
}

TEST(RandomizedSvd, SameBitsForAnyThreadCount) {
  const std::size_t m = 5000, n = 40;
  const auto data = low_rank(m, n, 12, 0.1, 5);
  RowSubsetMatrix a{data.data(), m, n, {}, {}};
  RandomizedSvdOptions o;
  o.rank = 9;
  TruncatedSvd one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = randomized_svd(a, o);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = randomized_svd(a, o);
  }
  ASSERT_EQ(one.basis.size(), two.basis.size());
  EXPECT_EQ(0, std::memcmp(one.basis.data(), two.basis.data(), sizeof(double) * one.basis.size()));
}

}  // namespace
}  // namespace clothbake::compress

// Clustered PCA (compress/cpca.hpp): exact recovery of data drawn from affine subspaces, strata
// never mixed, Sloan reclustering separating two subspaces, target-error rank allocation against
// the spectrum, and every stiff case (one row, constant, all zero, rank above the data).
#include <gtest/gtest.h>

#include <cmath>

#include "common/error.hpp"
#include "compress/cpca.hpp"
#include "model/splitmix64.hpp"

namespace clothbake::compress {
namespace {

// Rows of `groups` affine subspaces (dimension `rank` each) in `dim`; strata[i] from `stratum_of`.
struct Synthetic {
  std::size_t dim = 0;
  std::vector<float> rows;
  std::vector<uint8_t> strata;
  std::vector<int> group;
};

Synthetic make_synthetic(int groups, int per_group, std::size_t dim, int rank, uint64_t seed) {
  Synthetic s;
  s.dim = dim;
  model::SplitMix64 rng(seed);
  for (int g = 0; g < groups; ++g) {
    const Eigen::MatrixXd basis = gaussian_matrix(dim, std::size_t(rank), seed + 10 + g);
    const Eigen::VectorXd offset = 5.0 * gaussian_matrix(dim, 1, seed + 100 + g);
    for (int i = 0; i < per_group; ++i) {
      Eigen::VectorXd c(rank);
      for (int j = 0; j < rank; ++j)
        c[j] = 2.0 * rng.uniform() - 1.0;
      const Eigen::VectorXd x = offset + basis * c;
      for (std::size_t d = 0; d < dim; ++d)
        s.rows.push_back(float(x[Eigen::Index(d)]));
      s.strata.push_back(uint8_t(g / 2));  // two groups per stratum
      s.group.push_back(g);
    }
  }
  return s;
}

TEST(Cpca, RecoversAffineSubspacesExactlyAndRespectsStrata) {
  const Synthetic s = make_synthetic(4, 300, 48, 3, 7);
  CpcaOptions o;
  o.clusters_per_stratum = 2;
  o.rank = 3;
  const CpcaResult r = clustered_pca(s.rows.data(), s.strata.size(), s.dim, s.strata, o);
  ASSERT_EQ(r.cells.size(), 4u);
  for (const auto& cell : r.cells) {
    EXPECT_EQ(cell.rank(), 3);
    // One subspace per cell, inside one stratum.
    for (uint32_t row : cell.rows) {
      EXPECT_EQ(s.strata[row], cell.stratum);
      EXPECT_EQ(s.group[row], s.group[cell.rows.front()]);
    }
  }
  EXPECT_LT(r.relative_error(), 1e-4);
}

TEST(Cpca, OneCellPerStratumCannotFitTwoSubspacesAtThatRank) {
  const Synthetic s = make_synthetic(4, 300, 48, 3, 7);
  CpcaOptions o;
  o.clusters_per_stratum = 1;
  o.rank = 3;
  const CpcaResult r = clustered_pca(s.rows.data(), s.strata.size(), s.dim, s.strata, o);
  EXPECT_EQ(r.cells.size(), 2u);
  EXPECT_GT(r.relative_error(), 1e-2);  // the honest error of a model that does not fit
  // Two affine 3-D subspaces span at most 7 dimensions around the stratum mean.
  o.rank = 7;
  EXPECT_LT(clustered_pca(s.rows.data(), s.strata.size(), s.dim, s.strata, o).relative_error(),
            1e-4);
}

TEST(Cpca, TargetErrorTakesTheLargestComponentsFirst) {
  // One stratum, one cell: the residual after r components is the tail of the spectrum, so the
  // greedy choice must be the smallest r whose tail meets the target.
  const std::size_t m = 2000, dim = 30;
  std::vector<float> rows(m * dim);
  const Eigen::MatrixXd g = gaussian_matrix(m, dim, 3);
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t d = 0; d < dim; ++d)
      rows[i * dim + d] = float(g(Eigen::Index(i), Eigen::Index(d)) * std::pow(0.7, double(d)));
  std::vector<uint8_t> strata(m, 0);
  CpcaOptions fixed;
  fixed.rank = 30;
  const CpcaResult full = clustered_pca(rows.data(), m, dim, strata, fixed);
  ASSERT_EQ(full.cells.size(), 1u);
  const auto& cell = full.cells[0];
  std::vector<double> tail(31, 0.0);  // residual after r components
  for (int r = 29; r >= 0; --r)
    tail[std::size_t(r)] =
        tail[std::size_t(r) + 1] + double(cell.coefficients.col(r).cast<double>().squaredNorm());
  for (double target : {0.3, 0.1, 0.03}) {
    CpcaOptions o;
    o.rank = 30;
    o.target_error = target;
    const CpcaResult r = clustered_pca(rows.data(), m, dim, strata, o);
    int expected = 0;
    while (std::sqrt(tail[std::size_t(expected)] / full.total_energy) > target)
      ++expected;
    EXPECT_NEAR(r.cells[0].rank(), expected, 1) << target;
    EXPECT_LE(r.relative_error(), target * 1.0001);
  }
}

TEST(Cpca, StiffCases) {
  // One-row stratum, constant stratum, all-zero stratum, excluded rows, rank above the data.
  const std::size_t dim = 16;
  std::vector<float> rows;
  std::vector<uint8_t> strata;
  auto add = [&](uint8_t stratum, float value, float ramp) {
    for (std::size_t d = 0; d < dim; ++d)
      rows.push_back(value + ramp * float(d));
    strata.push_back(stratum);
  };
  add(0, 3.0f, 0.5f);  // stratum 0: one row
  for (int i = 0; i < 50; ++i)
    add(1, 2.0f, 0);  // stratum 1: constant rows
  for (int i = 0; i < 20; ++i)
    add(2, 0.0f, 0);  // stratum 2: all zero
  for (int i = 0; i < 5; ++i)
    add(255, 9.0f, 1);  // left out
  CpcaOptions o;
  o.clusters_per_stratum = 4;
  o.rank = 200;
  const CpcaResult r = clustered_pca(rows.data(), strata.size(), dim, strata, o);
  for (const auto& cell : r.cells) {
    EXPECT_EQ(cell.rank(), 0) << "stratum " << cell.stratum;  // numerical rank 0 everywhere
    for (float v : cell.mean)
      EXPECT_TRUE(std::isfinite(v));
    EXPECT_NE(cell.stratum, 255);
  }
  EXPECT_EQ(r.residual_energy, 0.0);
  EXPECT_EQ(r.relative_error(), 0.0);
  // Only the counted rows: 1 + 50 + 20 (the left-out ones are not in the total).
  double expected_total = 0;
  for (std::size_t i = 0; i + 5 < strata.size(); ++i)
    for (std::size_t d = 0; d < dim; ++d)
      expected_total += double(rows[i * dim + d]) * rows[i * dim + d];
  EXPECT_NEAR(r.total_energy, expected_total, 1e-9 * expected_total);
  // All rows zero: no NaN, error 0.
  std::vector<float> zeros(10 * dim, 0.0f);
  std::vector<uint8_t> zs(10, 0);
  o.target_error = 0.01;
  const CpcaResult z = clustered_pca(zeros.data(), 10, dim, zs, o);
  EXPECT_EQ(z.relative_error(), 0.0);
  EXPECT_EQ(z.total_energy, 0.0);
}

TEST(Cpca, RejectsOptionsOutOfRange) {
  std::vector<float> rows(4, 1.0f);
  std::vector<uint8_t> strata(2, 0);
  CpcaOptions o;
  o.clusters_per_stratum = 0;
  EXPECT_THROW(clustered_pca(rows.data(), 2, 2, strata, o), Error);
  o = {};
  o.rank = 256;
  EXPECT_THROW(clustered_pca(rows.data(), 2, 2, strata, o), Error);
  o = {};
  o.target_error = NAN;
  EXPECT_THROW(clustered_pca(rows.data(), 2, 2, strata, o), Error);
}

}  // namespace
}  // namespace clothbake::compress

// Randomized truncated SVD (Halko, Martinsson and Tropp 2011, "Finding structure with randomness",
// Alg. 4.4: randomized range finder with subspace (power) iterations, then the SVD of the small
// projected matrix) of a row subset of a float matrix, optionally centred by a given mean.
//
// Why randomized: the C-PCA of compress/cpca.hpp needs the leading r right singular vectors of
// matrices of up to 65536 x 1024 (texel vectors) or 8192 x 65536 (whole tables). The Gram matrix
// costs m n^2 (40-55 s for 8192^2 on this machine) and a full eigensolver minutes; the randomized
// range finder costs (2 q + 2) passes over the data with r + p columns, i.e. a few GEMMs.
//
// Determinism: the Gaussian test matrix comes from SplitMix64 (model/splitmix64.hpp) and
// Box-Muller, specified bit for bit; products run over fixed blocks of kSvdBlockRows rows (TBB,
// disjoint outputs), partial sums of A^T Q are added in block order, and Eigen's cache-blocking
// sizes are pinned (pin_eigen_blocking) so that GEMM sums in the same order on every machine. Same
// inputs, same bits, whatever the thread count.
//
// C++20. Safe for any finite input (all-zero data, rank larger than min(m, n), one row); inputs
// with NaN/Inf are the caller's error (compress checks its tables before).
#pragma once

#include <Eigen/Dense>
#include <cstddef>
#include <cstdint>
#include <span>

namespace clothbake::compress {

using RowMatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Rows processed per parallel block (products, projections).
inline constexpr std::size_t kSvdBlockRows = 1024;

// A = X[rows] - 1 mean^T: m = rows.size() rows of dimension dim taken from the row-major float
// matrix `data` (row i at data + i * dim). An empty `rows` means every row 0 .. row_count - 1.
// An empty `mean` means no centring. Not owned.
struct RowSubsetMatrix {
  const float* data = nullptr;
  std::size_t row_count = 0;  // rows of the underlying matrix
  std::size_t dim = 0;
  std::span<const uint32_t> rows;  // subset (indices < row_count), in the order used
  std::span<const float> mean;     // dim values or empty

  std::size_t rows_used() const { return rows.empty() ? row_count : rows.size(); }
  const float* row(std::size_t i) const {
    return data + (rows.empty() ? i : std::size_t(rows[i])) * dim;
  }
};

struct RandomizedSvdOptions {
  int rank = 10;             // r requested; clamped to min(m, n)
  int oversampling = 8;      // p extra random columns
  int power_iterations = 2;  // q subspace iterations (each re-orthonormalised)
  uint64_t seed = 1;
  // Optional warm start: up to r + p columns (dim rows, column-major) used as the first test
  // vectors instead of Gaussian ones (e.g. the previous C-PCA iteration's basis).
  const Eigen::MatrixXd* warm_start = nullptr;
};

struct TruncatedSvd {
  int rank = 0;               // columns of basis (<= requested rank)
  Eigen::MatrixXd basis;      // dim x rank, orthonormal right singular vectors
  Eigen::VectorXd singular;   // rank values, non-increasing, >= 0
  double total_energy = 0.0;  // ||A||_F^2 (double accumulation)
};

// Leading right singular vectors of A. Rank 0 (empty basis) when A has no rows or dim == 0.
// Columns whose singular value is 0 (data of lower rank) are kept (orthonormal, arbitrary): the
// caller's coefficients on them are 0.
TruncatedSvd randomized_svd(const RowSubsetMatrix& a, const RandomizedSvdOptions& options);

// coefficients (m x rank, row-major) = A basis, the orthogonal projection of each centred row.
// Also returns per row the squared residual ||a_i||^2 - ||coefficients_i||^2 (clamped at 0) if
// `residual2` is not empty (m values).
void project_rows(const RowSubsetMatrix& a, const Eigen::MatrixXd& basis, RowMatrixF* coefficients,
                  std::span<double> residual2 = {});

// Fixes Eigen's GEMM cache-blocking parameters (so that summation order, hence rounding, does not
// depend on the CPU's cache sizes). Called by randomized_svd; idempotent and thread-safe.
void pin_eigen_blocking();

// Deterministic standard normal matrix (rows x cols, column-major) from `seed`.
Eigen::MatrixXd gaussian_matrix(std::size_t rows, std::size_t cols, uint64_t seed);

}  // namespace clothbake::compress

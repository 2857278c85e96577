// Randomized truncated SVD (randomized_svd.hpp).
#include "compress/randomized_svd.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <vector>

#include "model/splitmix64.hpp"

namespace clothbake::compress {
namespace {

std::size_t block_count(std::size_t m) {
  return (m + kSvdBlockRows - 1) / kSvdBlockRows;
}

// Rows [begin, end) of A (uncentred) gathered into a dense block.
void gather(const RowSubsetMatrix& a, std::size_t begin, std::size_t end, RowMatrixF* out) {
  out->resize(Eigen::Index(end - begin), Eigen::Index(a.dim));
  for (std::size_t i = begin; i < end; ++i)
    std::copy(a.row(i), a.row(i) + a.dim, out->row(Eigen::Index(i - begin)).data());
}

Eigen::VectorXf mean_vector(const RowSubsetMatrix& a) {
  if (a.mean.empty()) return Eigen::VectorXf::Zero(Eigen::Index(a.dim));
  return Eigen::Map<const Eigen::VectorXf>(a.mean.data(), Eigen::Index(a.dim));
}

// Y = A W (m x l), W: dim x l.
Eigen::MatrixXd times(const RowSubsetMatrix& a, const Eigen::MatrixXd& w) {
  const std::size_t m = a.rows_used();
  const Eigen::MatrixXf wf = w.cast<float>();
  const Eigen::RowVectorXd mean_w = mean_vector(a).cast<double>().transpose() * w;
  Eigen::MatrixXd y(Eigen::Index(m), w.cols());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block_count(m), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      RowMatrixF block;
                      for (std::size_t b = r.begin(); b != r.end(); ++b) {
                        const std::size_t begin = b * kSvdBlockRows;
                        const std::size_t end = std::min(m, begin + kSvdBlockRows);
                        gather(a, begin, end, &block);
                        const Eigen::MatrixXf yb = block * wf;
                        y.middleRows(Eigen::Index(begin), Eigen::Index(end - begin)) =
                            yb.cast<double>().rowwise() - mean_w;
                      }
                    });
  return y;
}

// Z = A^T Q (dim x l), Q: m x l. Block partials summed in block order.
Eigen::MatrixXd transpose_times(const RowSubsetMatrix& a, const Eigen::MatrixXd& q) {
  const std::size_t m = a.rows_used();
  const std::size_t blocks = block_count(m);
  std::vector<Eigen::MatrixXd> partial(blocks);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        RowMatrixF block;
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          const std::size_t begin = b * kSvdBlockRows;
          const std::size_t end = std::min(m, begin + kSvdBlockRows);
          gather(a, begin, end, &block);
          const Eigen::MatrixXf qb =
              q.middleRows(Eigen::Index(begin), Eigen::Index(end - begin)).cast<float>();
          partial[b] = (block.transpose() * qb).cast<double>();
        }
      });
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(Eigen::Index(a.dim), q.cols());
  for (const auto& p : partial)
    z += p;
  if (!a.mean.empty()) z -= mean_vector(a).cast<double>() * q.colwise().sum();
  return z;
}

// Orthonormal basis of the columns of y (same shape; Householder, so rank-deficient input still
// gives orthonormal columns).
Eigen::MatrixXd orthonormalise(const Eigen::MatrixXd& y) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(y);
  return qr.householderQ() * Eigen::MatrixXd::Identity(y.rows(), y.cols());
}

double energy(const RowSubsetMatrix& a) {
  const std::size_t m = a.rows_used();
  const std::size_t blocks = block_count(m);
  std::vector<double> partial(blocks, 0.0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          const std::size_t begin = b * kSvdBlockRows;
          const std::size_t end = std::min(m, begin + kSvdBlockRows);
          double s = 0.0;
          for (std::size_t i = begin; i < end; ++i) {
            const float* row = a.row(i);
            for (std::size_t d = 0; d < a.dim; ++d) {
              const double v = double(row[d]) - (a.mean.empty() ? 0.0 : double(a.mean[d]));
              s += v * v;
            }
          }
          partial[b] = s;
        }
      });
  double total = 0.0;
  for (double p : partial)
    total += p;
  return total;
}

}  // namespace

void pin_eigen_blocking() {
  static std::once_flag once;
  std::call_once(once, [] { Eigen::setCpuCacheSizes(32 * 1024, 512 * 1024, 4 * 1024 * 1024); });
}

Eigen::MatrixXd gaussian_matrix(std::size_t rows, std::size_t cols, uint64_t seed) {
  model::SplitMix64 rng(seed);
  Eigen::MatrixXd g(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  double* p = g.data();
  const std::size_t count = rows * cols;
  for (std::size_t i = 0; i < count; i += 2) {
    // Box-Muller on (0, 1] x [0, 1): log never sees 0.
    const double u1 = 1.0 - rng.uniform();
    const double u2 = rng.uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    p[i] = radius * std::cos(2.0 * M_PI * u2);
    if (i + 1 < count) p[i + 1] = radius * std::sin(2.0 * M_PI * u2);
  }
  return g;
}

TruncatedSvd randomized_svd(const RowSubsetMatrix& a, const RandomizedSvdOptions& options) {
  pin_eigen_blocking();
  TruncatedSvd out;
  const std::size_t m = a.rows_used(), n = a.dim;
  if (m == 0 || n == 0 || options.rank < 1) return out;
  out.total_energy = energy(a);
  const int limit = int(std::min<std::size_t>(m, n));
  const int rank = std::min(options.rank, limit);
  const int width = std::min(limit, rank + std::max(0, options.oversampling));

  Eigen::MatrixXd omega = gaussian_matrix(n, std::size_t(width), options.seed);
  if (options.warm_start != nullptr && options.warm_start->rows() == Eigen::Index(n)) {
    const Eigen::Index w = std::min<Eigen::Index>(options.warm_start->cols(), width);
    omega.leftCols(w) = options.warm_start->leftCols(w);
  }
  Eigen::MatrixXd q = orthonormalise(times(a, omega));
  for (int it = 0; it < options.power_iterations; ++it) {
    const Eigen::MatrixXd z = orthonormalise(transpose_times(a, q));
    q = orthonormalise(times(a, z));
  }
  // B = Q^T A = Z^T with Z = A^T Q (n x l); A's right singular vectors are Z's left ones.
  const Eigen::MatrixXd z = transpose_times(a, q);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(z, Eigen::ComputeThinU);
  out.rank = rank;
  out.basis = svd.matrixU().leftCols(rank);
  out.singular = svd.singularValues().head(rank);
  // Deterministic sign: the largest-magnitude component of each basis vector is positive.
  for (int j = 0; j < rank; ++j) {
    Eigen::Index arg = 0;
    out.basis.col(j).cwiseAbs().maxCoeff(&arg);
    if (out.basis(arg, j) < 0) out.basis.col(j) = -out.basis.col(j);
  }
  return out;
}

void project_rows(const RowSubsetMatrix& a, const Eigen::MatrixXd& basis, RowMatrixF* coefficients,
                  std::span<double> residual2) {
  const std::size_t m = a.rows_used();
  const Eigen::Index rank = basis.cols();
  coefficients->resize(Eigen::Index(m), rank);
  if (rank == 0) {
    if (!residual2.empty()) {
      for (std::size_t i = 0; i < m; ++i) {
        double s = 0.0;
        const float* row = a.row(i);
        for (std::size_t d = 0; d < a.dim; ++d) {
          const double v = double(row[d]) - (a.mean.empty() ? 0.0 : double(a.mean[d]));
          s += v * v;
        }
        residual2[i] = s;
      }
    }
    return;
  }
  const Eigen::MatrixXf vf = basis.cast<float>();
  const Eigen::RowVectorXf mean_v = mean_vector(a).transpose() * vf;
  const Eigen::VectorXf mean = mean_vector(a);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, block_count(m), 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        RowMatrixF block;
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          const std::size_t begin = b * kSvdBlockRows;
          const std::size_t end = std::min(m, begin + kSvdBlockRows);
          gather(a, begin, end, &block);
          RowMatrixF cb = block * vf;
          cb.rowwise() -= mean_v;
          coefficients->middleRows(Eigen::Index(begin), Eigen::Index(end - begin)) = cb;
          if (residual2.empty()) continue;
          for (std::size_t i = begin; i < end; ++i) {
            const auto centred = block.row(Eigen::Index(i - begin)) - mean.transpose();
            const double norm2 = double(centred.squaredNorm());
            const double kept = double(cb.row(Eigen::Index(i - begin)).squaredNorm());
            residual2[i] = std::max(0.0, norm2 - kept);
          }
        }
      });
}

}  // namespace clothbake::compress

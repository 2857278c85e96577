// Clustered principal component analysis (C-PCA; Sloan, Hall, Hart and Snyder 2003, "Clustered
// principal components for precomputed radiance transfer"; used by the paper, Sec. 4.4, after Liu
// et al. 2004) of row vectors that are pre-partitioned into strata.
//
// Each stratum's rows are split into at most k cells; a cell approximates its rows by its mean
// plus an orthonormal rank-r_g basis, x ~ mean_g + V_g c with c = V_g^T (x - mean_g). Strata are
// the visibility clusters: a renderer asks for per-cluster answers, so a cell never straddles two
// of them (docs/compression.md explains why this costs nothing in size and keeps queries cheap).
//
// Algorithm, per stratum: a deterministic start (k-means++ with a fixed seed, cluster/kmeans.hpp,
// on the rows' coordinates in the stratum's leading principal subspace), then Sloan's iteration:
// fit every cell (mean + randomized truncated SVD, compress/randomized_svd.hpp, warm-started from
// the cell's previous basis), move every row to the cell that reconstructs it with the smallest
// error, repeat until no row moves or the iteration budget is spent. Cells that empty vanish.
//
// Ranks: fixed (r per cell, fewer when the data has lower numerical rank), or chosen for a
// target error: every cell is fitted at the rank cap, then components are taken greedily across
// all cells in order of the residual energy they remove (each cell's in its own order) until
// the relative RMS error sqrt(residual / total) reaches the target. Components that remove no
// energy (numerical rank reached) are never kept.
//
// Error measure: total = sum over all rows of ||x||^2 (uncentred), residual = sum of
// ||x - mean_g - V_g c||^2 (exact, from the orthogonal projection): relative_error() is the
// relative RMS error of the texel values.
//
// Deterministic for any thread count. C++20. Errors: clothbake::Error(Input) for options out of
// range; any finite data is accepted (all-zero, constant, one row, rank above the data's).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "compress/compress_settings.hpp"  // kMaxCpcaRank, kMaxCpcaClustersPerStratum
#include "compress/randomized_svd.hpp"

namespace clothbake::compress {

struct CpcaOptions {
  int clusters_per_stratum = 1;  // k, 1..64
  int rank = 16;                 // r per cell (fixed), or the cap when target_error > 0; 0..255
  double target_error = 0.0;     // > 0: choose ranks for this relative RMS error
  int iterations = 4;            // Sloan reclustering iterations (k > 1), >= 0
  int power_iterations = 2;      // randomized SVD subspace iterations
  int oversampling = 8;
  uint64_t seed = 1;
};

struct CpcaCell {
  int stratum = 0;
  std::vector<uint32_t> rows;   // row indices, ascending
  std::vector<float> mean;      // dim values
  Eigen::MatrixXd basis;        // dim x rank, orthonormal columns
  RowMatrixF coefficients;      // rows.size() x rank
  double centred_energy = 0.0;  // sum over rows of ||x - mean||^2
  double residual2 = 0.0;       // sum over rows of ||x - mean - basis c||^2
  int rank() const { return int(basis.cols()); }
};

struct CpcaResult {
  std::size_t dim = 0;
  std::vector<CpcaCell> cells;  // sorted by (stratum, first row)
  double total_energy = 0.0;    // sum over the rows in strata of ||x||^2
  double residual_energy = 0.0;
  int iterations = 0;       // largest number of reclustering iterations run in a stratum
  uint64_t moved_last = 0;  // rows moved by the last reclustering iteration (all strata)
  double relative_error() const;
  int total_rank() const;  // sum of cell ranks
};

// C-PCA of `rows` row vectors of dimension `dim` (row-major floats). strata[i] is row i's stratum
// (any value < 255), or 255 to leave the row out (it is not approximated; treat it as zero).
CpcaResult clustered_pca(const float* data, std::size_t rows, std::size_t dim,
                         std::span<const uint8_t> strata, const CpcaOptions& options);

}  // namespace clothbake::compress

// Clustered PCA with Sloan reclustering and greedy rank allocation (cpca.hpp).
#include "compress/cpca.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <queue>
#include <string>

#include "cluster/kmeans.hpp"
#include "common/error.hpp"

namespace clothbake::compress {
namespace {

// Components removing at most this fraction of a cell's centred energy are numerical noise.
constexpr double kNegligibleGain = 1e-12;
// Dimension of the subspace the k-means start works in.
constexpr int kSeedDims = 8;

std::vector<float> mean_of(const float* data, std::size_t dim, std::span<const uint32_t> rows) {
  std::vector<double> acc(dim, 0.0);
  for (uint32_t r : rows) {
    const float* x = data + std::size_t(r) * dim;
    for (std::size_t d = 0; d < dim; ++d)
      acc[d] += x[d];
  }
  std::vector<float> mean(dim, 0.0f);
  if (!rows.empty())
    for (std::size_t d = 0; d < dim; ++d)
      mean[d] = float(acc[d] / double(rows.size()));
  return mean;
}

struct Fit {
  std::vector<float> mean;
  Eigen::MatrixXd basis;
  double centred_energy = 0.0;
};

Fit fit_cell(const float* data, std::size_t row_count, std::size_t dim,
             std::span<const uint32_t> rows, int rank, const CpcaOptions& options,
             const Eigen::MatrixXd* warm, uint64_t seed) {
  Fit fit;
  fit.mean = mean_of(data, dim, rows);
  RowSubsetMatrix a{data, row_count, dim, rows, fit.mean};
  RandomizedSvdOptions svd_options;
  svd_options.rank = rank;
  svd_options.oversampling = options.oversampling;
  svd_options.power_iterations = options.power_iterations;
  svd_options.seed = seed;
  svd_options.warm_start = warm;
  TruncatedSvd svd = randomized_svd(a, svd_options);
  fit.basis = svd.rank > 0 ? svd.basis : Eigen::MatrixXd(Eigen::Index(dim), 0);
  fit.centred_energy = svd.rank > 0 ? svd.total_energy : 0.0;
  if (svd.rank == 0) {
    for (uint32_t r : rows) {
      const float* x = data + std::size_t(r) * dim;
      for (std::size_t d = 0; d < dim; ++d) {
        const double v = double(x[d]) - double(fit.mean[d]);
        fit.centred_energy += v * v;
      }
    }
  }
  return fit;
}

// Residual of every row of `rows` against one cell's (mean, basis).
void residuals(const float* data, std::size_t row_count, std::size_t dim,
               std::span<const uint32_t> rows, const Fit& fit, std::vector<double>* out) {
  out->assign(rows.size(), 0.0);
  RowSubsetMatrix a{data, row_count, dim, rows, fit.mean};
  RowMatrixF unused;
  project_rows(a, fit.basis, &unused, *out);
}

}  // namespace

double CpcaResult::relative_error() const {
  if (!(total_energy > 0.0)) return 0.0;
  return std::sqrt(std::max(0.0, residual_energy) / total_energy);
}

int CpcaResult::total_rank() const {
  int total = 0;
  for (const auto& c : cells)
    total += c.rank();
  return total;
}

CpcaResult clustered_pca(const float* data, std::size_t rows, std::size_t dim,
                         std::span<const uint8_t> strata, const CpcaOptions& options) {
  if (options.clusters_per_stratum < 1 || options.clusters_per_stratum > kMaxCpcaClustersPerStratum)
    throw_input_error("compress: C-PCA clusters per visibility cluster must be in [1, " +
                      std::to_string(kMaxCpcaClustersPerStratum) + "], got " +
                      std::to_string(options.clusters_per_stratum));
  if (options.rank < 0 || options.rank > kMaxCpcaRank)
    throw_input_error("compress: C-PCA rank must be in [0, " + std::to_string(kMaxCpcaRank) +
                      "], got " + std::to_string(options.rank));
  if (!(options.target_error >= 0.0) || !std::isfinite(options.target_error))
    throw_input_error("compress: the target error must be finite and >= 0");
  if (options.iterations < 0 || options.power_iterations < 0 || options.oversampling < 0)
    throw_input_error("compress: C-PCA iteration counts must be >= 0");
  if (strata.size() != rows) throw_internal_error("clustered_pca: strata size mismatch");
  pin_eigen_blocking();

  CpcaResult result;
  result.dim = dim;
  std::vector<std::vector<uint32_t>> by_stratum(256);
  for (std::size_t i = 0; i < rows; ++i)
    if (strata[i] != 255) by_stratum[strata[i]].push_back(uint32_t(i));
  {
    std::vector<double> partial((rows + kSvdBlockRows - 1) / kSvdBlockRows, 0.0);
    tbb::parallel_for(std::size_t(0), partial.size(), [&](std::size_t b) {
      double s = 0.0;
      for (std::size_t i = b * kSvdBlockRows; i < std::min(rows, (b + 1) * kSvdBlockRows); ++i) {
        if (strata[i] == 255) continue;
        const float* x = data + i * dim;
        for (std::size_t d = 0; d < dim; ++d)
          s += double(x[d]) * double(x[d]);
      }
      partial[b] = s;
    });
    for (double p : partial)
      result.total_energy += p;
  }

  const int k = options.clusters_per_stratum;
  for (int s = 0; s < 255; ++s) {
    const auto& members = by_stratum[std::size_t(s)];
    if (members.empty()) continue;
    const uint64_t stratum_seed = options.seed * 0x9e3779b97f4a7c15ull + uint64_t(s) + 1;

    // Deterministic start: k-means++ on the leading principal coordinates.
    std::vector<int32_t> labels(members.size(), 0);
    int cells_now = 1;
    if (k > 1 && members.size() > 1) {
      const Fit seed_fit =
          fit_cell(data, rows, dim, members, std::min(kSeedDims, std::max(1, options.rank)),
                   options, nullptr, stratum_seed);
      RowSubsetMatrix a{data, rows, dim, members, seed_fit.mean};
      RowMatrixF coords;
      project_rows(a, seed_fit.basis, &coords);
      if (coords.cols() > 0) {
        cluster::KMeansOptions km;
        km.clusters = int(std::min<std::size_t>(std::size_t(k), members.size()));
        km.seed = stratum_seed;
        km.max_iterations = 50;
        const auto clustering = cluster::kmeans(
            {coords.data(), std::size_t(coords.rows()), std::size_t(coords.cols())}, km);
        labels = clustering.labels;
        cells_now = clustering.clusters;
      }
    }

    // Sloan iterations: fit, reassign by reconstruction error.
    std::vector<Eigen::MatrixXd> previous(static_cast<std::size_t>(cells_now));
    for (int it = 0; cells_now > 1 && it < options.iterations; ++it) {
      std::vector<std::vector<uint32_t>> cell_rows(static_cast<std::size_t>(cells_now));
      for (std::size_t i = 0; i < members.size(); ++i)
        cell_rows[std::size_t(labels[i])].push_back(members[i]);
      std::vector<double> best(members.size(), INFINITY);
      std::vector<int32_t> next(members.size(), 0);
      std::vector<double> res;
      for (int g = 0; g < cells_now; ++g) {
        if (cell_rows[std::size_t(g)].empty()) continue;
        const int fit_rank = options.target_error > 0.0 ? std::min(options.rank, 16) : options.rank;
        const Fit fit =
            fit_cell(data, rows, dim, cell_rows[std::size_t(g)], fit_rank, options,
                     previous[std::size_t(g)].size() ? &previous[std::size_t(g)] : nullptr,
                     stratum_seed + uint64_t(g) * 7919);
        previous[std::size_t(g)] = fit.basis;
        residuals(data, rows, dim, members, fit, &res);
        for (std::size_t i = 0; i < members.size(); ++i)
          if (res[i] < best[i]) {  // strict: ties stay with the lower cell index
            best[i] = res[i];
            next[i] = g;
          }
      }
      uint64_t moved = 0;
      for (std::size_t i = 0; i < members.size(); ++i)
        moved += next[i] != labels[i];
      labels = next;
      result.iterations = std::max(result.iterations, it + 1);
      result.moved_last += moved;
      if (moved == 0) break;
    }

    // The non-empty cells, in order of their first row (fitted below).
    std::vector<std::vector<uint32_t>> cell_rows(static_cast<std::size_t>(cells_now));
    for (std::size_t i = 0; i < members.size(); ++i)
      cell_rows[std::size_t(labels[i])].push_back(members[i]);
    std::vector<CpcaCell> stratum_cells;
    for (int g = 0; g < cells_now; ++g) {
      if (cell_rows[std::size_t(g)].empty()) continue;
      CpcaCell cell;
      cell.stratum = s;
      cell.rows = std::move(cell_rows[std::size_t(g)]);
      if (previous[std::size_t(g)].size()) cell.basis = previous[std::size_t(g)];
      stratum_cells.push_back(std::move(cell));
    }
    std::sort(stratum_cells.begin(), stratum_cells.end(),
              [](const CpcaCell& a, const CpcaCell& b) { return a.rows.front() < b.rows.front(); });
    for (auto& c : stratum_cells)
      result.cells.push_back(std::move(c));
  }

  // Fit every cell at a rank cap and measure per component the energy it removes (the sum of its
  // squared coefficients). Fixed ranks: one fit at options.rank. Target error: caps 16, 32, 64,
  // ... up to options.rank, refitting only while the greedy allocation below saturates some cell
  // at the cap without reaching the target (most tables need far less than the cap).
  const std::size_t cell_count = result.cells.size();
  std::vector<std::vector<double>> gains(cell_count);
  std::vector<int> keep(cell_count, 0);
  const bool target = options.target_error > 0.0;
  const double goal = options.target_error * options.target_error * result.total_energy;
  int cap = target ? std::min(options.rank, 16) : options.rank;
  for (;;) {
    for (std::size_t g = 0; g < cell_count; ++g) {
      auto& c = result.cells[g];
      const Eigen::MatrixXd warm = c.basis;
      const Fit fit = fit_cell(
          data, rows, dim, c.rows, cap, options, warm.size() ? &warm : nullptr,
          options.seed * 0x9e3779b97f4a7c15ull + uint64_t(c.stratum) + 1 + uint64_t(g) * 7919);
      c.mean = fit.mean;
      c.basis = fit.basis;
      c.centred_energy = fit.centred_energy;
      RowSubsetMatrix a{data, rows, dim, c.rows, c.mean};
      project_rows(a, c.basis, &c.coefficients);
      gains[g].assign(std::size_t(c.rank()), 0.0);
      for (int j = 0; j < c.rank(); ++j)
        gains[g][std::size_t(j)] = double(c.coefficients.col(j).cast<double>().squaredNorm());
      // Numerical rank: stop at the first component that removes (almost) nothing.
      int useful = 0;
      while (useful < c.rank() &&
             gains[g][std::size_t(useful)] > kNegligibleGain * std::max(c.centred_energy, 1e-300))
        ++useful;
      keep[g] = useful;
    }
    if (!target) break;
    double residual = 0.0;
    for (const auto& c : result.cells)
      residual += c.centred_energy;
    std::vector<int> take(cell_count, 0);
    using Candidate = std::pair<double, std::size_t>;  // (gain, cell)
    auto worse = [](const Candidate& a, const Candidate& b) {
      return a.first < b.first || (a.first == b.first && a.second > b.second);
    };
    std::priority_queue<Candidate, std::vector<Candidate>, decltype(worse)> queue(worse);
    for (std::size_t g = 0; g < cell_count; ++g)
      if (keep[g] > 0) queue.push({gains[g][0], g});
    while (residual > goal && !queue.empty()) {
      const auto [gain, g] = queue.top();
      queue.pop();
      residual -= gain;
      ++take[g];
      if (take[g] < keep[g]) queue.push({gains[g][std::size_t(take[g])], g});
    }
    bool saturated = false;
    for (std::size_t g = 0; g < cell_count; ++g)
      saturated = saturated || (take[g] == cap && keep[g] == cap);
    if (residual <= goal || cap >= options.rank || !saturated) {
      keep = take;
      break;
    }
    cap = std::min(options.rank, cap * 2);
  }
  result.residual_energy = 0.0;
  for (std::size_t g = 0; g < cell_count; ++g) {
    auto& c = result.cells[g];
    const int r = keep[g];
    if (r < c.rank()) {
      c.basis = Eigen::MatrixXd(c.basis.leftCols(r));
      c.coefficients = RowMatrixF(c.coefficients.leftCols(r));
    }
    double kept = 0.0;
    for (int j = 0; j < r; ++j)
      kept += gains[g][std::size_t(j)];
    c.residual2 = std::max(0.0, c.centred_energy - kept);
    result.residual_energy += c.residual2;
  }
  return result;
}

}  // namespace clothbake::compress

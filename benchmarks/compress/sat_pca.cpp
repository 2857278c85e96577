// The paper's whole-SAT C-PCA layout, in memory (sat_pca.hpp).
#include "benchmarks/compress/sat_pca.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "compress/cpca.hpp"
#include "compress/half_float.hpp"

namespace clothbake::compress {

SatPcaModel SatPcaModel::fit(const DirectionalTexels& data, const SatPcaOptions& options) {
  SatPcaModel m;
  m.n_ = data.resolution;
  m.bins_per_side_ = data.bins_per_side;
  m.cluster_count_ = data.cluster_count;
  const std::size_t n = std::size_t(data.resolution), texels = n * n;
  const int bins = data.bins();
  m.column_of_cluster_.assign(std::size_t(data.cluster_count), -1);
  std::vector<int> columns;
  {
    std::vector<char> used(256, 0);
    for (uint8_t c : data.cluster)
      if (c != kNoStratum) used[c] = 1;
    for (int c = 0; c < data.cluster_count; ++c)
      if (used[std::size_t(c)]) {
        m.column_of_cluster_[std::size_t(c)] = int(columns.size());
        columns.push_back(c);
      }
  }
  const std::size_t tables = columns.size() * std::size_t(bins);
  std::vector<float> vectors(tables * texels);
  m.transform_.resize(tables);
  tbb::parallel_for(std::size_t(0), tables, [&](std::size_t t) {
    const int c = columns[t / std::size_t(bins)], b = int(t % std::size_t(bins));
    std::vector<float> table(texels, 0.0f);
    for (std::size_t x = 0; x < texels; ++x)
      if (data.cluster[x] == c) table[x] = data.values[x * std::size_t(bins) + std::size_t(b)];
    std::vector<double> sat(texels);
    summed_area_table(table.data(), int(n), sat.data());
    m.transform_[t] =
        normalise_sat(sat.data(), int(n), options.normalisation, vectors.data() + t * texels);
  });

  CpcaOptions cpca;
  cpca.clusters_per_stratum = options.clusters;
  cpca.rank = options.rank;
  cpca.iterations = options.iterations;
  cpca.seed = options.seed;
  const std::vector<uint8_t> strata(tables, 0);
  const CpcaResult result = clustered_pca(vectors.data(), tables, texels, strata, cpca);
  m.normalised_mse_ = tables ? result.residual_energy / (double(tables) * double(texels)) : 0.0;

  m.max_rank_ = 0;
  for (const auto& cell : result.cells)
    m.max_rank_ = std::max(m.max_rank_, cell.rank());
  m.table_group_.assign(tables, -1);
  m.coefficients_.assign(tables * std::size_t(m.max_rank_), 0.0f);
  for (std::size_t g = 0; g < result.cells.size(); ++g) {
    const auto& cell = result.cells[g];
    const int r = cell.rank();
    m.group_rank_.push_back(r);
    std::vector<float> images((1 + std::size_t(r)) * texels);
    auto store = [&](std::size_t image, auto value_at) {
      double peak = 0.0;
      for (std::size_t x = 0; x < texels; ++x)
        peak = std::max(peak, std::fabs(double(value_at(x))));
      for (std::size_t x = 0; x < texels; ++x) {
        const float unit = peak > 0 ? float(double(value_at(x)) / peak) : 0.0f;
        images[image * texels + x] =
            float(double(reader::half_to_float(float_to_half(unit))) * peak);
      }
    };
    store(0, [&](std::size_t x) { return cell.mean[x]; });
    for (int j = 0; j < r; ++j)
      store(1 + std::size_t(j), [&](std::size_t x) { return cell.basis(Eigen::Index(x), j); });
    m.images_.push_back(std::move(images));
    for (std::size_t i = 0; i < cell.rows.size(); ++i) {
      const std::size_t t = cell.rows[i];
      m.table_group_[t] = int(g);
      for (int j = 0; j < r; ++j)
        m.coefficients_[t * std::size_t(m.max_rank_) + std::size_t(j)] =
            cell.coefficients(Eigen::Index(i), j);
    }
  }
  return m;
}

uint64_t SatPcaModel::stored_bytes() const {
  uint64_t bytes = 0;
  const uint64_t texels = uint64_t(n_) * uint64_t(n_);
  for (int r : group_rank_)
    bytes += (1 + uint64_t(r)) * texels * 2;
  for (std::size_t t = 0; t < table_group_.size(); ++t)
    bytes += 4 + 3 * 8 +
             (table_group_[t] >= 0 ? uint64_t(group_rank_[std::size_t(table_group_[t])]) * 4 : 0);
  return bytes;
}

double SatPcaModel::corner(int column, int bin, int i, int j) const {
  if (i <= 0 || j <= 0) return 0.0;
  const std::size_t t =
      std::size_t(column) * std::size_t(bins_per_side_ * bins_per_side_) + std::size_t(bin);
  const int g = table_group_[t];
  const std::size_t texels = std::size_t(n_) * std::size_t(n_);
  const std::size_t x = std::size_t(j - 1) * std::size_t(n_) + std::size_t(i - 1);
  double stored = 0.0;
  if (g >= 0) {
    const auto& images = images_[std::size_t(g)];
    stored = images[x];
    for (int r = 0; r < group_rank_[std::size_t(g)]; ++r)
      stored += double(coefficients_[t * std::size_t(max_rank_) + std::size_t(r)]) *
                double(images[(1 + std::size_t(r)) * texels + x]);
  }
  return transform_[t].restore(stored, i - 1, j - 1);
}

bool SatPcaModel::query(const reader::Footprint& rect, const double h[3], int cluster,
                        double* out) const {
  reader::FootprintPlan plan;
  reader::BinWeights bw;
  if (!reader::make_footprint_plan(rect, uint32_t(n_), &plan) ||
      !reader::make_bin_weights(uint32_t(bins_per_side_), h, &bw) || cluster < 0 ||
      cluster >= cluster_count_)
    return false;
  const int column = column_of_cluster_[std::size_t(cluster)];
  if (column < 0) {
    *out = 0.0;
    return true;
  }
  const double size = double(n_);
  auto at = [&](int bin, double x, double y) {  // bilinear SAT at a real corner
    const int i = x >= size ? n_ - 1 : int(x), j = y >= size ? n_ - 1 : int(y);
    const double a = x - i, b = y - j;
    return (1 - a) * (1 - b) * corner(column, bin, i, j) +
           a * (1 - b) * corner(column, bin, i + 1, j) +
           (1 - a) * b * corner(column, bin, i, j + 1) + a * b * corner(column, bin, i + 1, j + 1);
  };
  double total = 0.0;
  for (uint32_t w = 0; w < bw.count; ++w) {
    const int b = int(bw.bin[w]);
    double f = at(b, plan.rx1, plan.ry1) - at(b, plan.x0, plan.ry1) - at(b, plan.rx1, plan.y0) +
               at(b, plan.x0, plan.y0);
    if (plan.qx > 0) f += plan.qx * (at(b, size, plan.ry1) - at(b, size, plan.y0));
    if (plan.qy > 0) f += plan.qy * (at(b, plan.rx1, size) - at(b, plan.x0, size));
    if (plan.qx > 0 && plan.qy > 0) f += plan.qx * plan.qy * at(b, size, size);
    total += bw.weight[w] * f;
  }
  *out = total;
  return true;
}

}  // namespace clothbake::compress

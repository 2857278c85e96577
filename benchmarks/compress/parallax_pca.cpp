// Principal components of the parallax table (parallax_pca.hpp).
#include "benchmarks/compress/parallax_pca.hpp"

#include "compress/parallax_codes.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "compress/randomized_svd.hpp"
#include "model/directions.hpp"

namespace clothbake::compress {
namespace {

constexpr std::size_t kBlockTexels = 1024;

// Offset error of one texel's decoded vector against the raw codes, accumulated.
struct ErrorSums {
  double sum2 = 0.0, max_offset = 0.0, max_depth = 0.0;
  uint64_t above = 0;
};

}  // namespace

std::vector<double> parallax_offset_weights(int resolution, int dirs, double min_cos) {
  // N tan(theta) per bin (the codes' own factor), floored so that the nadir bin still counts.
  std::vector<double> w = parallax_offset_per_depth(resolution, dirs, min_cos);
  for (double& x : w)
    x = std::max(x, double(resolution) * kParallaxMinWeight);
  return w;
}

void measure_parallax_pca_error(const ParallaxCodes& raw, ParallaxPca* p) {
  const std::size_t n = std::size_t(raw.resolution), texels = n * n;
  const std::size_t d = std::size_t(raw.dirs) * raw.dirs;
  const int k = p->rank;
  // Offset length per unit r at the bin centres (no floor: the true Eq. 2 offset).
  const model::DirectionGrid<double> grid{raw.dirs, raw.min_cos};
  std::vector<double> tan_n(d);
  for (int j = 0; j < raw.dirs; ++j)
    for (int i = 0; i < raw.dirs; ++i) {
      const model::Vec3d o = grid.bin_center(i, j);
      tan_n[std::size_t(grid.bin_index(i, j))] = double(n) * std::sqrt(o.x * o.x + o.y * o.y) / o.z;
    }
  const std::size_t blocks = (texels + kBlockTexels - 1) / kBlockTexels;
  std::vector<ErrorSums> sums(blocks);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks), [&](const auto& range) {
    std::vector<double> row(d);
    for (std::size_t b = range.begin(); b != range.end(); ++b) {
      ErrorSums s;
      for (std::size_t t = b * kBlockTexels; t < std::min(texels, (b + 1) * kBlockTexels); ++t) {
        for (std::size_t e = 0; e < d; ++e)
          row[e] = double(p->basis[e]);
        const int16_t* q = p->coefficients.data() + t * std::size_t(k);
        for (int c = 0; c < k; ++c) {
          const float* basis = p->basis.data() + std::size_t(c + 1) * d;
          const double qc = double(q[c]);
          for (std::size_t e = 0; e < d; ++e)
            row[e] += qc * double(basis[e]);
        }
        for (std::size_t e = 0; e < d; ++e) {
          const double r = -double(raw.codes[e * texels + t]) * raw.depth_scale;
          const double dr = std::fabs(row[e] - r), off = dr * tan_n[e];
          s.sum2 += off * off;
          s.max_offset = std::max(s.max_offset, off);
          s.max_depth = std::max(s.max_depth, dr);
          if (off > 0.25) ++s.above;
        }
      }
      sums[b] = s;
    }
  });
  ErrorSums total;
  for (const ErrorSums& s : sums) {  // block order: deterministic
    total.sum2 += s.sum2;
    total.max_offset = std::max(total.max_offset, s.max_offset);
    total.max_depth = std::max(total.max_depth, s.max_depth);
    total.above += s.above;
  }
  const double entries = double(texels) * double(d);
  p->rms_offset_error = std::sqrt(total.sum2 / entries);
  p->max_offset_error = total.max_offset;
  p->max_depth_error = total.max_depth;
  p->share_above_quarter = double(total.above) / entries;
}

namespace {

// Quantises the projections of every texel on basis columns [0, rank) and fills `p`.
void store(const ParallaxCodes& raw, const std::vector<double>& w, const std::vector<float>& mean,
           const Eigen::MatrixXd& basis, const RowMatrixF& coeffs, int rank, ParallaxPca* p) {
  const std::size_t texels = std::size_t(raw.resolution) * raw.resolution;
  const std::size_t d = w.size();
  p->rank = rank;
  p->basis.assign(std::size_t(rank + 1) * d, 0.0f);
  p->coefficients.assign(texels * std::size_t(rank), 0);
  for (std::size_t e = 0; e < d; ++e)
    p->basis[e] = float(double(mean[e]) / w[e]);
  for (int c = 0; c < rank; ++c) {
    double peak = 0.0;
    for (std::size_t t = 0; t < texels; ++t)
      peak = std::max(peak, std::fabs(double(coeffs(Eigen::Index(t), c))));
    const double step = peak > 0.0 ? peak / 32767.0 : 0.0;
    for (std::size_t e = 0; e < d; ++e)
      p->basis[std::size_t(c + 1) * d + e] = float(basis(Eigen::Index(e), c) * step / w[e]);
    if (step > 0.0)
      for (std::size_t t = 0; t < texels; ++t) {
        const double q = std::nearbyint(double(coeffs(Eigen::Index(t), c)) / step);
        p->coefficients[t * std::size_t(rank) + std::size_t(c)] =
            int16_t(std::clamp(q, -32767.0, 32767.0));
      }
  }
}

}  // namespace

ParallaxPca fit_parallax_pca(const ParallaxCodes& raw, const ParallaxPcaOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!(options.max_error > 0.0 && options.max_error <= 1.0))
    throw_input_error("bake.parallax_max_error must be in (0, 1] texels, got " +
                      std::to_string(options.max_error));
  if (options.rank_cap < 0 || options.rank_cap > int(kMaxParallaxPcaRank) ||
      options.fixed_rank > int(kMaxParallaxPcaRank))
    throw_input_error("parallax compression: rank out of range 0.." +
                      std::to_string(kMaxParallaxPcaRank));
  if (raw.resolution < 1 || raw.dirs < 1 || raw.codes == nullptr)
    throw_input_error("parallax compression: empty table");
  const std::size_t n = std::size_t(raw.resolution), texels = n * n;
  const std::size_t d = std::size_t(raw.dirs) * raw.dirs;
  ParallaxPca p;
  p.resolution = raw.resolution;
  p.dirs = raw.dirs;
  p.min_cos = raw.min_cos;
  p.reference_height = raw.reference_height;
  p.max_offset = raw.max_offset;

  const std::vector<double> w = parallax_offset_weights(raw.resolution, raw.dirs, raw.min_cos);
  // y = w r, texel-major (the PCA's rows are texels).
  std::vector<float> y(texels * d);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, texels, kBlockTexels), [&](const auto& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      for (std::size_t e = 0; e < d; ++e)
        y[t * d + e] = float(-double(raw.codes[e * texels + t]) * raw.depth_scale * w[e]);
  });
  // The mean over texels (in block order, double).
  std::vector<double> acc(d, 0.0);
  for (std::size_t t = 0; t < texels; ++t)
    for (std::size_t e = 0; e < d; ++e)
      acc[e] += y[t * d + e];
  std::vector<float> mean(d);
  for (std::size_t e = 0; e < d; ++e)
    mean[e] = float(acc[e] / double(texels));

  const int cap = options.fixed_rank >= 0 ? options.fixed_rank : options.rank_cap;
  RowSubsetMatrix a{y.data(), texels, d, {}, mean};
  TruncatedSvd svd;
  if (cap > 0) {
    RandomizedSvdOptions so;
    so.rank = cap;
    so.power_iterations = options.power_iterations;
    so.seed = options.seed;
    svd = randomized_svd(a, so);
  }
  const int have = svd.rank;
  // Smallest rank whose exact PCA residual meets the target, in offset texels^2.
  const double entries = double(texels) * double(d);
  const double target2 = options.max_error * options.max_error * entries;
  int rank = have;
  if (options.fixed_rank < 0) {
    double residual = svd.total_energy;
    rank = 0;
    while (rank < have && residual > target2) {
      residual -= svd.singular(rank) * svd.singular(rank);
      ++rank;
    }
  } else {
    rank = std::min(options.fixed_rank, have);
  }
  RowMatrixF coeffs;
  if (have > 0) project_rows(a, svd.basis, &coeffs);
  for (;;) {
    store(raw, w, mean, svd.basis, coeffs, rank, &p);
    measure_parallax_pca_error(raw, &p);
    if (options.fixed_rank >= 0 || p.rms_offset_error <= options.max_error || rank >= have) break;
    ++rank;  // quantisation pushed the error above the target
  }
  p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return p;
}

}  // namespace clothbake::compress

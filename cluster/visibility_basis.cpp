// Per-cluster principal components of the texels' visibility (visibility_basis.hpp).
#include "cluster/visibility_basis.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <string>

#include "common/error.hpp"
#include "model/directions.hpp"

namespace clothbake::cluster {
namespace {

// The bit pattern of one texel's ASG parameters: texels with equal keys have equal visibility.
using AsgKey = std::array<uint32_t, 7>;
AsgKey key_of(const model::AsgParams<float>& p) {
  const float v[7] = {p.axis.x, p.axis.y, p.axis.z, p.rotation, p.lambda, p.mu, p.amplitude};
  AsgKey k;
  std::memcpy(k.data(), v, sizeof v);
  return k;
}

constexpr std::size_t kBlock = 1024;  // patterns per block of the sums

}  // namespace

VisibilityBasis fit_visibility_basis(int resolution, std::span<const model::AsgParams<float>> asgs,
                                     std::span<const uint8_t> labels, int clusters, int dirs,
                                     int rank) {
  const std::size_t texels = std::size_t(std::max(resolution, 0)) * std::size_t(resolution);
  if (resolution < 1 || asgs.size() != texels || labels.size() != texels)
    throw_input_error("visibility basis: " + std::to_string(asgs.size()) + " ASGs and " +
                      std::to_string(labels.size()) + " labels for a " +
                      std::to_string(resolution) + "^2 map");
  if (clusters < 1 || clusters > 255)
    throw_input_error("visibility basis: clusters = " + std::to_string(clusters) +
                      " is outside [1, 255]");
  if (dirs < 1 || dirs > 256)
    throw_input_error("visibility basis: dirs = " + std::to_string(dirs) + " is outside [1, 256]");
  if (rank < 0 || rank > kMaxVisibilityRank)
    throw_input_error("visibility basis: rank = " + std::to_string(rank) + " is outside [0, " +
                      std::to_string(kMaxVisibilityRank) + "]");
  for (std::size_t t = 0; t < texels; ++t)
    if (labels[t] >= clusters)
      throw_input_error("visibility basis: texel " + std::to_string(t) + " has label " +
                        std::to_string(labels[t]) + " >= " + std::to_string(clusters));

  const int bins = dirs * dirs;
  const model::DirectionGrid<float> grid{dirs, 0.0f};
  std::vector<model::Vec3f> centres(bins);
  for (int b = 0; b < bins; ++b)
    centres[b] = grid.bin_center(b % dirs, b / dirs);

  // Distinct visibility patterns per cluster (ordered map: a deterministic order), with counts.
  std::vector<std::map<AsgKey, std::size_t>> index(clusters);
  std::vector<std::vector<std::size_t>> first(clusters);  // a texel of each pattern
  std::vector<std::vector<double>> count(clusters);
  std::vector<std::size_t> pattern_of(texels);
  for (std::size_t t = 0; t < texels; ++t) {
    const int c = labels[t];
    auto [it, fresh] = index[c].emplace(key_of(asgs[t]), first[c].size());
    if (fresh) {
      first[c].push_back(t);
      count[c].push_back(0.0);
    }
    count[c][it->second] += 1.0;
    pattern_of[t] = it->second;
  }

  VisibilityBasis out;
  out.resolution = resolution;
  out.clusters = clusters;
  out.dirs = dirs;
  out.rank = rank;
  out.components.assign(std::size_t(clusters) * std::size_t(rank + 1) * std::size_t(bins), 0.0f);
  out.coefficients.assign(texels * std::size_t(rank), 0.0f);
  out.explained_fraction.assign(clusters, 1.0);
  // Per cluster and pattern: the coefficients, scattered to the texels afterwards.
  std::vector<Eigen::MatrixXf> pattern_coefficients(clusters);

  tbb::parallel_for(tbb::blocked_range<int>(0, clusters, 1), [&](const tbb::blocked_range<int>& r) {
    for (int c = r.begin(); c != r.end(); ++c) {
      const std::size_t patterns = first[c].size();
      if (patterns == 0) continue;
      // V of a block of patterns at every bin centre (memory: kBlock x bins doubles).
      auto block_values = [&](std::size_t begin, std::size_t end, Eigen::MatrixXd& v) {
        v.resize(Eigen::Index(end - begin), bins);
        for (std::size_t p = begin; p < end; ++p) {
          const model::Asg<float> g = model::asg_from_params(asgs[first[c][p]]);
          for (int b = 0; b < bins; ++b)
            v(Eigen::Index(p - begin), b) =
                std::clamp(double(model::asg_eval(g, centres[b])), 0.0, 1.0);
        }
      };
      const Eigen::Map<const Eigen::VectorXd> w(count[c].data(), Eigen::Index(patterns));
      Eigen::MatrixXd v;
      Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(bins);
      for (std::size_t begin = 0; begin < patterns; begin += kBlock) {
        const std::size_t end = std::min(patterns, begin + kBlock);
        block_values(begin, end, v);
        mean += w.segment(Eigen::Index(begin), Eigen::Index(end - begin)).transpose() * v;
      }
      mean /= w.sum();
      float* comp = &out.components[std::size_t(c) * std::size_t(rank + 1) * std::size_t(bins)];
      for (int b = 0; b < bins; ++b)
        comp[b] = float(mean[b]);
      if (rank == 0) continue;
      Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(bins, bins);
      for (std::size_t begin = 0; begin < patterns; begin += kBlock) {
        const std::size_t end = std::min(patterns, begin + kBlock);
        block_values(begin, end, v);
        v.rowwise() -= mean;
        cov += v.transpose() *
               w.segment(Eigen::Index(begin), Eigen::Index(end - begin)).asDiagonal() * v;
      }
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
      const double variance = std::max(cov.trace(), 0.0);
      double captured = 0.0;
      Eigen::MatrixXd basis = Eigen::MatrixXd::Zero(bins, rank);
      for (int k = 0; k < rank && k < bins; ++k) {
        const Eigen::Index col = Eigen::Index(bins - 1 - k);
        Eigen::VectorXd b = eig.eigenvectors().col(col);
        captured += std::max(eig.eigenvalues()[col], 0.0);
        Eigen::Index largest = 0;
        b.cwiseAbs().maxCoeff(&largest);
        if (b[largest] < 0.0) b = -b;
        basis.col(k) = b;
      }
      for (int k = 0; k < rank; ++k)
        for (int bin = 0; bin < bins; ++bin)
          comp[std::size_t(k + 1) * std::size_t(bins) + std::size_t(bin)] = float(basis(bin, k));
      pattern_coefficients[c].resize(Eigen::Index(patterns), rank);
      for (std::size_t begin = 0; begin < patterns; begin += kBlock) {
        const std::size_t end = std::min(patterns, begin + kBlock);
        block_values(begin, end, v);
        v.rowwise() -= mean;
        pattern_coefficients[c].middleRows(Eigen::Index(begin), Eigen::Index(end - begin)) =
            (v * basis).cast<float>();
      }
      out.explained_fraction[c] = variance > 0.0 ? std::min(1.0, captured / variance) : 1.0;
    }
  });
  if (rank > 0)
    for (std::size_t t = 0; t < texels; ++t) {
      const Eigen::MatrixXf& e = pattern_coefficients[labels[t]];
      for (int k = 0; k < rank; ++k)
        out.coefficients[t * std::size_t(rank) + std::size_t(k)] =
            e(Eigen::Index(pattern_of[t]), k);
    }
  return out;
}

}  // namespace clothbake::cluster

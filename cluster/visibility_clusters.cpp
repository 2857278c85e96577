// Visibility clusters and per-cluster mean visibility (visibility_clusters.hpp).
#include "cluster/visibility_clusters.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "model/directions.hpp"

namespace clothbake::cluster {

BinDirections hemisphere_bin_directions(int dirs, int samples_per_bin_side) {
  const int s = samples_per_bin_side;
  model::DirectionGrid<double> grid{dirs, 0.0};
  BinDirections out;
  out.dirs = dirs;
  out.samples_per_bin = s * s;
  const std::size_t total = std::size_t(dirs) * std::size_t(dirs) * std::size_t(s * s);
  out.x.reserve(total);
  out.y.reserve(total);
  out.z.reserve(total);
  for (int j = 0; j < dirs; ++j)
    for (int i = 0; i < dirs; ++i)
      for (int q = 0; q < s; ++q)
        for (int p = 0; p < s; ++p) {
          const double u = (i + (p + 0.5) / s) / dirs, v = (j + (q + 0.5) / s) / dirs;
          const model::Vec3d d = grid.direction(u, v);
          out.x.push_back(float(d.x));
          out.y.push_back(float(d.y));
          out.z.push_back(float(d.z));
        }
  return out;
}

void asg_bin_averages(const model::Asg<float>& g, const BinDirections& directions, float* out) {
  const int bins = directions.dirs * directions.dirs;
  const int per_bin = directions.samples_per_bin;
  const float inv = 1.0f / float(per_bin);
  const float* dx = directions.x.data();
  const float* dy = directions.y.data();
  const float* dz = directions.z.data();
  for (int b = 0; b < bins; ++b) {
    float sum = 0.0f;
    for (int k = b * per_bin; k < (b + 1) * per_bin; ++k) {
      const float vz = g.z.x * dx[k] + g.z.y * dy[k] + g.z.z * dz[k];
      const float vx = g.x.x * dx[k] + g.x.y * dy[k] + g.x.z * dz[k];
      const float vy = g.y.x * dx[k] + g.y.y * dy[k] + g.y.z * dz[k];
      const float value = g.amplitude * std::exp(-g.lambda * vx * vx - g.mu * vy * vy);
      sum += vz > 0.0f ? value : 0.0f;
    }
    out[b] = sum * inv;
  }
}

namespace {

void check_options(int resolution, std::size_t asg_count, const VisibilityClusterOptions& o) {
  if (resolution < 1) throw_input_error("visibility clusters: resolution must be at least 1");
  const std::size_t texels = std::size_t(resolution) * std::size_t(resolution);
  if (asg_count != texels)
    throw_input_error("visibility clusters: " + std::to_string(asg_count) + " ASGs for a " +
                      std::to_string(resolution) + "^2 map (" + std::to_string(texels) +
                      " texels)");
  if (o.clusters < 1 || o.clusters > kMaxVisibilityClusters)
    throw_input_error("visibility clusters: clusters = " + std::to_string(o.clusters) +
                      " is outside [1, " + std::to_string(kMaxVisibilityClusters) + "]");
  if (o.visibility_dirs < 1 || o.visibility_dirs > 256)
    throw_input_error("visibility clusters: visibility_dirs = " +
                      std::to_string(o.visibility_dirs) + " is outside [1, 256]");
  if (o.samples_per_bin_side < 1 || o.samples_per_bin_side > 16)
    throw_input_error("visibility clusters: samples per bin side = " +
                      std::to_string(o.samples_per_bin_side) + " is outside [1, 16]");
}

constexpr std::size_t kTexelBlock = 1024;

}  // namespace

VisibilityClusters cluster_visibility(int resolution, std::span<const model::AsgParams<float>> asgs,
                                      const VisibilityClusterOptions& options) {
  check_options(resolution, asgs.size(), options);
  const std::vector<float> embedding = embed_asgs(asgs, options.weights);

  KMeansOptions kopt;
  kopt.clusters = options.clusters;
  kopt.max_iterations = options.max_iterations;
  kopt.seed = options.seed;
  VisibilityClusters out;
  out.kmeans = kmeans(PointSet{embedding.data(), asgs.size(), kAsgEmbeddingDim}, kopt);
  out.resolution = resolution;
  out.clusters = out.kmeans.clusters;
  out.visibility_dirs = options.visibility_dirs;
  out.samples_per_bin_side = options.samples_per_bin_side;
  out.labels.resize(asgs.size());
  // Per cluster: texels and inertia (squared embedding distance to the texel's K-means centre).
  std::vector<uint64_t> sizes;
  std::vector<double> inertia;
  if (options.split_by.empty()) {
    for (std::size_t i = 0; i < asgs.size(); ++i)
      out.labels[i] = uint8_t(out.kmeans.labels[i]);
    sizes = out.kmeans.sizes;
    inertia = out.kmeans.inertia;
  } else {
    if (options.split_by.size() != asgs.size())
      throw_input_error("visibility clusters: " + std::to_string(options.split_by.size()) +
                        " split groups for " + std::to_string(asgs.size()) + " texels");
    std::map<std::pair<int32_t, uint16_t>, int> ids;
    for (std::size_t i = 0; i < asgs.size(); ++i)
      ids.emplace(std::make_pair(out.kmeans.labels[i], options.split_by[i]), 0);
    if (ids.size() > std::size_t(kMaxVisibilityClusters))
      throw_input_error("visibility clusters: splitting " + std::to_string(out.clusters) +
                        " clusters by yarn gives " + std::to_string(ids.size()) +
                        " clusters, more than " + std::to_string(kMaxVisibilityClusters) +
                        "; lower [bake] clusters or set clusters_by_yarn = false");
    int next = 0;
    for (auto& entry : ids)
      entry.second = next++;
    out.clusters = next;
    sizes.assign(std::size_t(next), 0);
    inertia.assign(std::size_t(next), 0.0);
    for (std::size_t i = 0; i < asgs.size(); ++i) {
      const int32_t k = out.kmeans.labels[i];
      const int c = ids.at(std::make_pair(k, options.split_by[i]));
      out.labels[i] = uint8_t(c);
      sizes[std::size_t(c)] += 1;
      double d2 = 0.0;
      for (std::size_t j = 0; j < kAsgEmbeddingDim; ++j) {
        const double d = double(embedding[i * kAsgEmbeddingDim + j]) -
                         out.kmeans.centres[std::size_t(k) * kAsgEmbeddingDim + j];
        d2 += d * d;
      }
      inertia[std::size_t(c)] += d2;
    }
  }

  // Per block of texels: sum and sum of squares of V(x, b) per (cluster, bin), in double.
  const BinDirections directions =
      hemisphere_bin_directions(options.visibility_dirs, options.samples_per_bin_side);
  const std::size_t bins =
      std::size_t(options.visibility_dirs) * std::size_t(options.visibility_dirs);
  const std::size_t k = std::size_t(out.clusters);
  const std::size_t texels = asgs.size();
  const std::size_t blocks = (texels + kTexelBlock - 1) / kTexelBlock;
  std::vector<double> block_sum(blocks * k * bins, 0.0), block_sq(blocks * k * bins, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::vector<float> v(bins);
                      for (std::size_t b = range.begin(); b != range.end(); ++b) {
                        double* sum = &block_sum[b * k * bins];
                        double* sq = &block_sq[b * k * bins];
                        const std::size_t end = std::min(texels, (b + 1) * kTexelBlock);
                        for (std::size_t x = b * kTexelBlock; x < end; ++x) {
                          const model::Asg<float> g = model::asg_from_params(asgs[x]);
                          asg_bin_averages(g, directions, v.data());
                          const std::size_t c = out.labels[x];
                          for (std::size_t d = 0; d < bins; ++d) {
                            sum[c * bins + d] += v[d];
                            sq[c * bins + d] += double(v[d]) * double(v[d]);
                          }
                        }
                      }
                    });
  std::vector<double> sum(k * bins, 0.0), sq(k * bins, 0.0);
  for (std::size_t b = 0; b < blocks; ++b)
    for (std::size_t t = 0; t < k * bins; ++t) {
      sum[t] += block_sum[b * k * bins + t];
      sq[t] += block_sq[b * k * bins + t];
    }

  // Global mean per bin, cluster means, and the variances from the sums.
  std::vector<double> global_mean(bins, 0.0);
  for (std::size_t c = 0; c < k; ++c)
    for (std::size_t d = 0; d < bins; ++d)
      global_mean[d] += sum[c * bins + d];
  for (double& m : global_mean)
    m /= double(texels);
  out.mean_visibility.resize(k * bins);
  out.stats.resize(k);
  double total_var = 0.0, total_res = 0.0;
  for (std::size_t c = 0; c < k; ++c) {
    const double n = double(sizes[c]);
    double var = 0.0, res = 0.0;
    for (std::size_t d = 0; d < bins; ++d) {
      const double s = sum[c * bins + d], q = sq[c * bins + d];
      const double mean = s / n;
      out.mean_visibility[c * bins + d] = float(mean);
      // sum (V - m)^2 = q - 2 m s + n m^2, clamped at 0 against rounding.
      res += std::max(0.0, q - s * mean);
      const double g = global_mean[d];
      var += std::max(0.0, q - 2.0 * g * s + n * g * g);
    }
    ClusterStats& st = out.stats[c];
    st.texels = sizes[c];
    st.inertia = inertia[c];
    st.variance = var / (n * double(bins));
    st.residual_variance = res / (n * double(bins));
    st.explained_fraction = var > 0.0 ? 1.0 - res / var : 1.0;
    total_var += var;
    total_res += res;
  }
  out.variance = total_var / (double(texels) * double(bins));
  out.residual_variance = total_res / (double(texels) * double(bins));
  out.explained_fraction = total_var > 0.0 ? 1.0 - total_res / total_var : 1.0;
  return out;
}

}  // namespace clothbake::cluster

// Clustered control variates, the precompute side (paper Sec. 4.2, Eq. 8): K-means on the
// per-texel ASG visibility lobes gives a label map; each cluster c gets its average visibility
// v_c(w) over a grid of light directions, the constant of the control variate that a renderer
// multiplies with the cluster's Integral-Radiance answer F_c.
//
// Mean visibility from the ASGs, not from the raw visibility samples: the renderer evaluates the
// residual of Eq. 8, D(p) (V(p, i) - v_c(i)), with V(p, i) from the texel's ASG (that is all the
// asset stores per texel), so the v_c that minimises the residual's energy is the cluster mean of
// the ASG visibility itself. The ASGs are also smooth and defined for every direction, so each bin
// gets a true bin average (an s x s stratified rule over the bin's square cell, equal weights
// because the grid is equal-area), grazing bins included, instead of one ray per bin.
//
// Bins: DirectionGrid{visibility_dirs, 0} over the upper hemisphere of light directions (bin
// (i, j) at index j * dirs + i). Explained variance: with V(x, b) the bin average of texel x's ASG
// over bin b, the total variance is the mean over texels and bins of (V(x, b) - V(b))^2 (V(b) the
// mean over all texels) and the residual variance the mean of (V(x, b) - v_c(x)(b))^2; the
// explained fraction 1 - residual / total is the share of the per-texel visibility variation that
// the cluster means capture (the rest is left to the Monte Carlo residual). The same quantities
// restricted to one cluster's texels are reported per cluster.
//
// Deterministic for any thread count (fixed blocks, fixed-order sums). C++20.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "cluster/asg_embedding.hpp"
#include "cluster/kmeans.hpp"
#include "model/asg.hpp"

namespace clothbake::cluster {

inline constexpr int kMaxVisibilityClusters = 255;  // labels are stored as u8

struct VisibilityClusterOptions {
  int clusters = 8;              // N_c requested, 1..255
  uint64_t seed = 1;             // k-means++ seed
  int max_iterations = 100;      // Lloyd budget
  int visibility_dirs = 32;      // mean-visibility grid: dirs x dirs hemisphere bins, 1..256
  int samples_per_bin_side = 2;  // s: s x s stratified ASG samples per bin, 1..16
  AsgEmbeddingWeights weights;   // embedding weights
  // Optional group per texel (N^2 values, e.g. the yarn id): when given, every K-means cluster is
  // split by group, so that no cluster spans two groups. The clusters are then the occurring
  // (K-means cluster, group) pairs, numbered in that lexicographic order (at most 255).
  std::span<const uint16_t> split_by;
};

struct ClusterStats {
  uint64_t texels = 0;
  double inertia = 0.0;             // K-means inertia in embedding space
  double variance = 0.0;            // mean (V(x,b) - V(b))^2 over the cluster's texels and bins
  double residual_variance = 0.0;   // mean (V(x,b) - v_c(b))^2 over the same
  double explained_fraction = 1.0;  // 1 - residual / variance (1 if variance is 0)
};

struct VisibilityClusters {
  int resolution = 0;       // N (labels has N * N entries, row-major)
  int clusters = 0;         // non-empty clusters actually produced
  int visibility_dirs = 0;  // n: mean_visibility has clusters * n * n entries
  int samples_per_bin_side = 0;
  std::vector<uint8_t> labels;         // per texel, in [0, clusters)
  std::vector<float> mean_visibility;  // [cluster][bin], bin averages in [0, kAsgMaxAmplitude]
  std::vector<ClusterStats> stats;     // per cluster
  double variance = 0.0;               // over all texels
  double residual_variance = 0.0;
  double explained_fraction = 1.0;
  KMeansResult kmeans;  // labels/centres in embedding space, iterations, ...
};

// Clusters the N x N per-texel ASGs (row-major). Errors (clothbake::Error, Input): asgs.size() !=
// N * N, N < 1, options out of range, a non-finite ASG parameter (naming the texel), split_by of
// the wrong size or a split into more than 255 clusters.
VisibilityClusters cluster_visibility(int resolution, std::span<const model::AsgParams<float>> asgs,
                                      const VisibilityClusterOptions& options);

// The s x s stratified light directions of every bin of DirectionGrid{dirs, 0}, bin-major (bin b's
// samples at [b * s * s, (b + 1) * s * s)), structure of arrays.
struct BinDirections {
  int dirs = 0;
  int samples_per_bin = 0;  // s * s
  std::vector<float> x, y, z;
};
BinDirections hemisphere_bin_directions(int dirs, int samples_per_bin_side);

// Bin averages of one ASG over every bin of `directions` (dirs * dirs values written to out).
void asg_bin_averages(const model::Asg<float>& asg, const BinDirections& directions, float* out);

}  // namespace clothbake::cluster

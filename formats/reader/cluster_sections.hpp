// Visibility clusters of an asset (paper Sec. 4.2): the per-texel cluster label map and each
// cluster's mean visibility v_c(w), the control-variate constant of Eq. 8.
//
// Sections (version 1; docs/tables.md):
//   ClusterLabels         instance 0: u8 {N, N}, label of texel (x, y) at y * N + x, < C
//   ClusterMeanVisibility instance 0: f32 {C, n, n}, bin averages of the clusters' ASG visibility
//                                     over DirectionGrid{n, 0} of light directions (upper
//                                     hemisphere, bin (i, j) at j * n + i), values in [0, 2]
// C (clusters) is the first dimension of the mean visibility; every cluster has at least one
// texel.
//
// The clusters' visibility basis (cluster/visibility_basis.hpp, docs/format.md §6.8):
//   ClusterVisibilityBasis instance 0: f32 {C, M + 1, n, n}: per cluster c, component 0 the mean
//                          m_c and components 1..M the principal directions b_ck of the clamped
//                          ASG visibility at the bin centres of DirectionGrid{n, 0}
//   ClusterVisibilityBasis instance 1: f32 {N, N, M}: texel (x, y)'s coefficients e_k at
//                          (y N + x) M + k - 1 (absent when M = 0)
// so that V(x, w) ~ m_c(w) + sum_k e_k(x) b_ck(w), each component bilinear between bin centres.
//
// C++17, standard library only, noexcept, no allocation; safe on untrusted assets that
// Asset::open accepted (shapes and label range are checked by open()).
#pragma once

#include <cstdint>

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

inline constexpr uint32_t kMaxVisibilityClusters = 255;
inline constexpr uint32_t kMaxVisibilityDirs = 256;

class VisibilityClusterView {
 public:
  // Errors: NotFound (CBK-E019), WrongType/Unsupported (CBK-E015: version, type, shape),
  // Malformed (CBK-E021: a label >= C, a non-finite or out-of-range mean visibility, a cluster
  // without texels).
  Status open(const Asset& asset) noexcept;
  bool is_open() const noexcept { return labels_ != nullptr; }

  uint32_t resolution() const noexcept { return n_; }
  uint32_t cluster_count() const noexcept { return clusters_; }
  uint32_t visibility_dirs() const noexcept { return dirs_; }

  // Label of texel (x, y); coordinates wrap (any integers).
  uint32_t label(int64_t x, int64_t y) const noexcept;
  // Label of texel index t = y N + x (t < N^2, no wrapping).
  uint32_t label_at(uint64_t t) const noexcept { return labels_[t]; }
  // Bin average of cluster c's visibility in bin `bin` (< dirs^2).
  float mean_visibility_bin(uint32_t cluster, uint32_t bin) const noexcept {
    return mean_[uint64_t(cluster) * dirs_ * dirs_ + bin];
  }
  // v_c(w): bilinear between bin centres for a light direction w (any non-zero vector; directions
  // below the horizon take the rim bins). InvalidArgument for a bad cluster or a zero/non-finite w.
  Status mean_visibility(uint32_t cluster, const double w[3], double* out) const noexcept;

 private:
  const uint8_t* labels_ = nullptr;
  const float* mean_ = nullptr;
  uint32_t n_ = 0, clusters_ = 0, dirs_ = 0;
};

inline constexpr uint32_t kMaxVisibilityBasisRank = 16;

class VisibilityBasisView {
 public:
  // Errors: NotFound (CBK-E019: no cluster_visibility_basis instance 0), WrongType/Unsupported
  // (CBK-E015: version, type, shape: instance 0 {C, M + 1, n, n} with 1 <= C <= 255,
  // 0 <= M <= 16, 1 <= n <= 256; instance 1 {N, N, M}, present exactly when M > 0), Malformed
  // (CBK-E021: a non-finite value; CBK-E017 is the writer's). The caller checks that C and N
  // agree with the label map (the evaluator reports CBK-E022 otherwise).
  Status open(const Asset& asset) noexcept;
  bool is_open() const noexcept { return components_ != nullptr; }

  uint32_t cluster_count() const noexcept { return clusters_; }
  uint32_t rank() const noexcept { return rank_; }
  uint32_t dirs() const noexcept { return dirs_; }
  uint32_t resolution() const noexcept { return n_; }  // 0 when rank() is 0

  // Component k (0: the mean, 1..M) of cluster c at bin `bin` (< dirs^2). Preconditions: c <
  // cluster_count(), k <= rank().
  float component(uint32_t c, uint32_t k, uint32_t bin) const noexcept {
    return components_[((uint64_t(c) * (rank_ + 1) + k) * dirs_ + 0) * dirs_ + bin];
  }
  // The M coefficients of texel index t = y N + x (t < N^2); null when M = 0.
  const float* coefficients(uint64_t t) const noexcept {
    return coefficients_ ? coefficients_ + t * rank_ : nullptr;
  }

 private:
  const float* components_ = nullptr;
  const float* coefficients_ = nullptr;
  uint32_t clusters_ = 0, rank_ = 0, dirs_ = 0, n_ = 0;
};

}  // namespace clothbake::reader

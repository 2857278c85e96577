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

}  // namespace clothbake::reader

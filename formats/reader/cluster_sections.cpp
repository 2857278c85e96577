// Visibility cluster sections: label map and mean visibility (cluster_sections.hpp).
#include "formats/reader/cluster_sections.hpp"

#include <cmath>

#include "formats/reader/detail/open_sections.hpp"
#include "model/directions.hpp"

namespace clothbake::reader {

Status VisibilityClusterView::open(const Asset& asset) noexcept {
  *this = VisibilityClusterView();
  ArrayView<uint8_t> labels;
  ArrayView<float> mean;
  Status s = detail::view_required_pair(
      asset, {SectionType::ClusterLabels, 0}, {SectionType::ClusterMeanVisibility, 0},
      "this asset has no visibility clusters (cluster_labels and cluster_mean_visibility)",
      "cluster sections: payload version must be 1", &labels, &mean);
  if (!s.ok()) return s;
  if (labels.rank != 2 || labels.dims[0] != labels.dims[1] || labels.dims[0] == 0)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "cluster_labels must be u8 {N, N}");
  if (mean.rank != 3 || mean.dims[0] == 0 || mean.dims[0] > kMaxVisibilityClusters ||
      mean.dims[1] != mean.dims[2] || mean.dims[1] == 0 || mean.dims[1] > kMaxVisibilityDirs)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "cluster_mean_visibility must be f32 {C, n, n} with 1 <= C <= 255 and "
                         "1 <= n <= 256");
  const uint32_t clusters = mean.dims[0];
  uint64_t seen[4] = {0, 0, 0, 0};  // bit set of labels that occur
  for (uint64_t t = 0; t < labels.size; ++t) {
    const uint32_t l = labels[t];
    if (l >= clusters)
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "cluster_labels: texel (%llu, %llu) has label %u >= %u clusters",
                           static_cast<unsigned long long>(t % labels.dims[0]),
                           static_cast<unsigned long long>(t / labels.dims[0]), unsigned(l),
                           unsigned(clusters));
    seen[l / 64] |= uint64_t(1) << (l % 64);
  }
  for (uint32_t c = 0; c < clusters; ++c)
    if (!(seen[c / 64] >> (c % 64) & 1))
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "cluster_labels: cluster %u has no texel", unsigned(c));
  for (uint64_t t = 0; t < mean.size; ++t)
    if (!(mean[t] >= 0.0f && mean[t] <= 2.0f))
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "cluster_mean_visibility: value %llu is not in [0, 2]",
                           static_cast<unsigned long long>(t));
  labels_ = labels.data;
  mean_ = mean.data;
  n_ = labels.dims[0];
  clusters_ = clusters;
  dirs_ = mean.dims[1];
  return {};
}

Status VisibilityBasisView::open(const Asset& asset) noexcept {
  *this = VisibilityBasisView();
  ArrayView<float> components, coefficients;
  bool present = false;
  Status s = detail::view_optional(asset, {SectionType::ClusterVisibilityBasis, 0},
                                   "cluster_visibility_basis: payload version must be 1",
                                   &components, &present);
  if (!s.ok()) return s;
  if (!present)
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "this asset has no cluster_visibility_basis");
  if (components.rank != 4 || components.dims[0] == 0 ||
      components.dims[0] > kMaxVisibilityClusters || components.dims[1] == 0 ||
      components.dims[1] > kMaxVisibilityBasisRank + 1 ||
      components.dims[2] != components.dims[3] || components.dims[2] == 0 ||
      components.dims[2] > kMaxVisibilityDirs)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "cluster_visibility_basis instance 0 must be f32 {C, M + 1, n, n} with "
                         "1 <= C <= 255, 0 <= M <= 16 and 1 <= n <= 256");
  const uint32_t rank = components.dims[1] - 1;
  s = detail::view_optional(asset, {SectionType::ClusterVisibilityBasis, 1},
                            "cluster_visibility_basis: payload version must be 1", &coefficients,
                            &present);
  if (!s.ok()) return s;
  if (present != (rank > 0) ||
      (present && (coefficients.rank != 3 || coefficients.dims[0] != coefficients.dims[1] ||
                   coefficients.dims[0] == 0 || coefficients.dims[2] != rank)))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "cluster_visibility_basis instance 1 must be f32 {N, N, M} exactly when "
                         "M = %u > 0",
                         unsigned(rank));
  // The ranges that follow from the definitions (docs/format.md §6.8), with a margin for float
  // rounding: a mean of clamped visibilities lies in [0, 1], a unit vector's entries in [-1, 1],
  // and a coefficient, the dot product of a unit vector with one of n^2 entries in [-1, 1], within
  // n of 0. Finite values far outside them once overflowed the evaluator's sums.
  constexpr double kMargin = 1e-4;
  const uint64_t grid = uint64_t(components.dims[2]) * components.dims[3];
  for (uint64_t k = 0; k < components.size; ++k) {
    const double v = components[k];
    const bool mean = (k / grid) % (uint64_t(rank) + 1) == 0;
    if (!(mean ? v >= -kMargin && v <= 1 + kMargin : std::fabs(v) <= 1 + kMargin))
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "cluster_visibility_basis: component value %llu (%g) is not finite or "
                           "outside %s",
                           static_cast<unsigned long long>(k), v, mean ? "[0, 1]" : "[-1, 1]");
  }
  const double max_coefficient = double(components.dims[2]) * (1 + kMargin) + kMargin;
  if (present)
    for (uint64_t k = 0; k < coefficients.size; ++k)
      if (!(std::fabs(double(coefficients[k])) <= max_coefficient))
        return Status::error(ErrorCode::Malformed, Check::ValueRange,
                             "cluster_visibility_basis: coefficient %llu (%g) is not finite or "
                             "beyond the grid's side %u",
                             static_cast<unsigned long long>(k), double(coefficients[k]),
                             unsigned(components.dims[2]));
  components_ = components.data;
  coefficients_ = present ? coefficients.data : nullptr;
  clusters_ = components.dims[0];
  rank_ = rank;
  dirs_ = components.dims[2];
  n_ = present ? coefficients.dims[0] : 0;
  return {};
}

uint32_t VisibilityClusterView::label(int64_t x, int64_t y) const noexcept {
  const int64_t n = int64_t(n_);
  int64_t xm = x % n, ym = y % n;
  if (xm < 0) xm += n;
  if (ym < 0) ym += n;
  return labels_[uint64_t(ym) * n_ + uint64_t(xm)];
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
Status VisibilityClusterView::mean_visibility(uint32_t cluster, const double w[3],
                                              double* out) const noexcept {
  if (!is_open() || out == nullptr || w == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "mean_visibility: not open");
  if (cluster >= clusters_)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "mean_visibility: cluster %u out of range (%u clusters)",
                         unsigned(cluster), unsigned(clusters_));
  if (!std::isfinite(w[0]) || !std::isfinite(w[1]) || !std::isfinite(w[2]) ||
      !(w[0] * w[0] + w[1] * w[1] + w[2] * w[2] > 0.0))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "mean_visibility: direction must be finite and non-zero");
  const model::DirectionGrid<double> grid{int(dirs_), 0.0};
  const model::BinBilinear<double> b = grid.bilinear(model::Vec3d(w[0], w[1], w[2]));
  double v = 0.0;
  for (int k = 0; k < 4; ++k)
    v += b.weight[k] * mean_visibility_bin(cluster, uint32_t(b.index[k]));
  *out = v;
  return {};
}
#endif

}  // namespace clothbake::reader

// Raw Integral-Radiance tables of an asset (layout: radiance_layout.hpp), with the footprint
// queries of radiance_query.hpp answered exactly from the fixed-point SATs: the integer parts of
// the SAT corners are combined in integer arithmetic (no cancellation), only the fractional
// coverage of partial texels and the final scaling use floating point.
//
// C++17, standard library only, noexcept, no allocation. open() checks every section's version,
// element type and shape against the info record, the cluster ids and the units before any
// query can index the data (safe on untrusted assets that Asset::open accepted); check_contents()
// additionally scans the whole SAT (O(size)) for tables that could not come from non-negative
// data. Views point into the Asset, which must outlive this object.
#pragma once

#include <cstdint>

#include "formats/reader/asset.hpp"
#include "formats/reader/radiance_layout.hpp"
#include "formats/reader/radiance_query.hpp"

namespace clothbake::reader {

class RawRadianceTables final : public RadianceTables {
 public:
  // Opens kind's tables. Errors: NotFound (CBK-E019: the kind is not in the asset), WrongType /
  // Unsupported / Malformed (CBK-E015: bad version, element type, shape or record), ValueRange
  // (CBK-E021: cluster ids not ascending or out of range, a unit not finite and positive).
  Status open(const Asset& asset, RadianceTableKind kind) noexcept;
  bool is_open() const noexcept { return info_ != nullptr; }

  RadianceTableKind kind() const noexcept override { return kind_; }
  uint32_t resolution() const noexcept override { return n_; }
  uint32_t bins_per_side() const noexcept override { return bins_per_side_; }
  uint32_t cluster_count() const noexcept override { return cluster_count_; }
  bool try_query(const Footprint& rect, const double h[3], uint32_t cluster,
                 double* out) const noexcept override;
  bool try_query_all(const Footprint& rect, const double h[3], double* out) const noexcept override;

  const RadianceTableInfoRecord& info() const noexcept { return *info_; }
  uint32_t stored_clusters() const noexcept { return columns_; }
  // Cluster id of stored column k (< stored_clusters()).
  uint32_t cluster_of_column(uint32_t k) const noexcept { return cluster_ids_[k]; }
  // Column of a cluster id, or -1 when the cluster has no stored table.
  int column_of_cluster(uint32_t cluster) const noexcept {
    return cluster < cluster_count_ ? column_of_[cluster] : -1;
  }
  // Value of one integer step of (bin, column).
  double unit(uint32_t bin, uint32_t column) const noexcept {
    return units_[uint64_t(bin) * columns_ + column];
  }
  // Inclusive SAT element Sat[bin][y][x][column] as an integer (x, y < N).
  uint64_t sat_element(uint32_t bin, uint32_t x, uint32_t y, uint32_t column) const noexcept;
  // Exact table value T of one texel (x, y < N) of (bin, column): its quantised integer times the
  // unit (what the SAT sums).
  double texel_value(uint32_t bin, uint32_t x, uint32_t y, uint32_t column) const noexcept;

  // The table of one (bin, cluster) as an image: N * N floats, texel (x, y) at y * N + x, the
  // per-texel values T[cluster][bin] (not the SAT), for looking at a table (`clothbake export`).
  // Clusters without a stored table give zeros. InvalidArgument for a bad bin or cluster.
  Status texel_image(uint32_t bin, uint32_t cluster, float* out) const noexcept;

  // O(size) scan: every texel's integer (recovered from the SAT by the 2 x 2 difference) must be
  // non-negative, i.e. the SAT is non-decreasing in x and y. ValueRange (CBK-E021) naming the
  // first offending bin, texel and cluster otherwise.
  Status check_contents() const noexcept;
  // O(size) scan against the label map (labels: N x N, texel (x, y) at y * N + x): every texel
  // whose label is not a column's cluster holds 0 in that column (T[c] = ... * [label = c]).
  // Check::CrossSection (CBK-E022) naming the first offending bin, texel and cluster
  // otherwise; InvalidArgument when not open or labels is null.
  Status check_against_labels(const uint8_t* labels) const noexcept;

 private:
  template <class E>
  bool query_impl(const Footprint& rect, const double h[3], int column, double* out) const noexcept;

  const RadianceTableInfoRecord* info_ = nullptr;
  RadianceTableKind kind_ = RadianceTableKind::Specular;
  uint32_t n_ = 0, bins_per_side_ = 0, cluster_count_ = 0, columns_ = 0, element_bits_ = 0;
  const uint32_t* cluster_ids_ = nullptr;
  const double* units_ = nullptr;
  const void* sat_ = nullptr;
  int16_t column_of_[kMaxRadianceClusters + 1] = {};
};

}  // namespace clothbake::reader

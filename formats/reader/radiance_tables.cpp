// Raw Integral-Radiance tables: opening with checks, exact fixed-point footprint queries
// (radiance_tables.hpp).
#include "formats/reader/radiance_tables.hpp"

#include <cinttypes>
#include <cmath>

namespace clothbake::reader {
namespace {

Status layout_error(const char* what, RadianceTableKind kind, const char* detail) noexcept {
  return Status::error(ErrorCode::WrongType, Check::SectionLayout, "radiance_tables %s (%s): %s",
                       radiance_kind_name(kind) ? radiance_kind_name(kind) : "?", what, detail);
}

Status find_part(const Asset& asset, RadianceTableKind kind, RadiancePart part,
                 SectionInfo* out) noexcept {
  Status s = asset.find(SectionType::RadianceRawTables, radiance_instance(kind, part), out);
  if (s.code() == ErrorCode::NotFound)
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "radiance_tables: the %s tables are not in this asset (part %u missing)",
                         radiance_kind_name(kind) ? radiance_kind_name(kind) : "?", unsigned(part));
  if (!s.ok()) return s;
  if (out->version != 1)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "radiance_tables part %u: payload version %u is not 1", unsigned(part),
                         unsigned(out->version));
  return {};
}

// One SAT point (x, y) in [0, N]^2: the offsets of S(i, j), S(i+1, j), S(i, j+1), S(i+1, j+1)
// (column 0; -1 where the SAT is zero because i or j is 0) and the fractions a, b.
struct PointLookup {
  int64_t off[4];
  double a, b;
};

inline PointLookup lookup(double x, double y, uint32_t n, uint32_t columns) noexcept {
  uint32_t i = x >= double(n) ? n - 1 : uint32_t(x);
  uint32_t j = y >= double(n) ? n - 1 : uint32_t(y);
  PointLookup p;
  p.a = x - double(i);
  p.b = y - double(j);
  auto offset = [&](uint32_t ii, uint32_t jj) -> int64_t {
    if (ii == 0 || jj == 0) return -1;
    return (int64_t(jj - 1) * int64_t(n) + int64_t(ii - 1)) * int64_t(columns);
  };
  p.off[0] = offset(i, j);
  p.off[1] = offset(i + 1, j);
  p.off[2] = offset(i, j + 1);
  p.off[3] = offset(i + 1, j + 1);
  return p;
}

// Accumulates sign * I(point) for columns [0, count) of `base` (one bin, column `first`):
// integer part (wrapping uint64, exact) and fractional part (double).
template <class E>
inline void accumulate(const E* base, const PointLookup& p, uint32_t first, uint32_t count,
                       int sign, uint64_t* ip, double* fp) noexcept {
  const double ab = p.a * p.b;
  const bool frac = p.a != 0.0 || p.b != 0.0;
  for (uint32_t k = 0; k < count; ++k) {
    const uint64_t s00 = p.off[0] < 0 ? 0 : uint64_t(base[p.off[0] + first + k]);
    if (sign > 0)
      ip[k] += s00;
    else
      ip[k] -= s00;
    if (!frac) continue;
    const uint64_t s10 = p.off[1] < 0 ? 0 : uint64_t(base[p.off[1] + first + k]);
    const uint64_t s01 = p.off[2] < 0 ? 0 : uint64_t(base[p.off[2] + first + k]);
    const uint64_t s11 = p.off[3] < 0 ? 0 : uint64_t(base[p.off[3] + first + k]);
    const double d10 = double(int64_t(s10 - s00));
    const double d01 = double(int64_t(s01 - s00));
    const double d11 = double(int64_t(s11 - s10 - s01 + s00));
    const double f = p.a * d10 + p.b * d01 + ab * d11;
    fp[k] += sign > 0 ? f : -f;
  }
}

}  // namespace

Status RawRadianceTables::open(const Asset& asset, RadianceTableKind kind) noexcept {
  *this = RawRadianceTables();
  kind_ = kind;
  if (uint32_t(kind) >= kRadianceKindCount)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "unknown radiance table kind %u",
                         unsigned(kind));
  SectionInfo info_s, clusters_s, units_s, sat_s;
  Status s = find_part(asset, kind, RadiancePart::Info, &info_s);
  if (s.ok()) s = find_part(asset, kind, RadiancePart::Clusters, &clusters_s);
  if (s.ok()) s = find_part(asset, kind, RadiancePart::Units, &units_s);
  if (s.ok()) s = find_part(asset, kind, RadiancePart::Sat, &sat_s);
  if (!s.ok()) return s;

  ArrayView<uint8_t> info_bytes;
  s = asset.view_of(info_s, &info_bytes);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(RadianceTableInfoRecord))
    return layout_error("info", kind, "must be u8 {1, 64}");
  const auto* info = reinterpret_cast<const RadianceTableInfoRecord*>(info_bytes.data);
  if (info->kind != uint32_t(kind)) return layout_error("info", kind, "kind field does not match");
  if (info->resolution == 0 || info->resolution > kMaxRadianceResolution)
    return layout_error("info", kind, "resolution out of range");
  if (info->bins_per_side == 0 || info->bins_per_side > kMaxRadianceBinsPerSide)
    return layout_error("info", kind, "bins_per_side out of range");
  if (kind == RadianceTableKind::Gap && info->bins_per_side != 1)
    return layout_error("info", kind, "the gap table has exactly one bin");
  if (info->cluster_count == 0 || info->cluster_count > kMaxRadianceClusters)
    return layout_error("info", kind, "cluster_count out of range");
  if (info->stored_clusters == 0 || info->stored_clusters > info->cluster_count)
    return layout_error("info", kind, "stored_clusters out of range");
  if (info->element_bits != 32 && info->element_bits != 64)
    return layout_error("info", kind, "element_bits must be 32 or 64");
  const uint32_t n = info->resolution, columns = info->stored_clusters;
  const uint32_t bins = info->bins_per_side * info->bins_per_side;

  ArrayView<uint32_t> ids;
  s = asset.view_of(clusters_s, &ids);
  if (!s.ok()) return s;
  if (ids.rank != 1 || ids.dims[0] != columns)
    return layout_error("clusters", kind, "must be u32 {stored_clusters}");
  for (uint32_t k = 0; k < columns; ++k)
    if (ids[k] >= info->cluster_count || (k > 0 && ids[k] <= ids[k - 1]))
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "radiance_tables %s: cluster id %u at column %u is out of range or not "
                           "ascending",
                           radiance_kind_name(kind), unsigned(ids[k]), unsigned(k));

  ArrayView<double> units;
  s = asset.view_of(units_s, &units);
  if (!s.ok()) return s;
  if (units.rank != 2 || units.dims[0] != bins || units.dims[1] != columns)
    return layout_error("units", kind, "must be f64 {bins, stored_clusters}");
  for (uint64_t t = 0; t < units.size; ++t)
    if (!(units[t] > 0.0) || !(units[t] <= 1e100))
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "radiance_tables %s: unit of bin %" PRIu64 " column %" PRIu64
                           " is not in (0, 1e100]",
                           radiance_kind_name(kind), t / columns, t % columns);

  const void* sat = nullptr;
  const uint32_t* dims = nullptr;
  uint16_t rank = 0;
  ArrayView<uint32_t> sat32;
  ArrayView<uint64_t> sat64;
  if (info->element_bits == 32) {
    s = asset.view_of(sat_s, &sat32);
    sat = sat32.data;
    dims = sat32.dims;
    rank = sat32.rank;
  } else {
    s = asset.view_of(sat_s, &sat64);
    sat = sat64.data;
    dims = sat64.dims;
    rank = sat64.rank;
  }
  if (!s.ok()) {
    s.prefix("radiance_tables sat (element_bits does not match the section)");
    return s;
  }
  if (rank != 4 || dims[0] != bins || dims[1] != n || dims[2] != n || dims[3] != columns)
    return layout_error("sat", kind, "must be {bins, N, N, stored_clusters}");

  info_ = info;
  n_ = n;
  bins_per_side_ = info->bins_per_side;
  cluster_count_ = info->cluster_count;
  columns_ = columns;
  element_bits_ = info->element_bits;
  cluster_ids_ = ids.data;
  units_ = units.data;
  sat_ = sat;
  for (uint32_t c = 0; c <= kMaxRadianceClusters; ++c)
    column_of_[c] = -1;
  for (uint32_t k = 0; k < columns; ++k)
    column_of_[ids[k]] = int16_t(k);
  return {};
}

uint64_t RawRadianceTables::sat_element(uint32_t bin, uint32_t x, uint32_t y,
                                        uint32_t column) const noexcept {
  const uint64_t index = ((uint64_t(bin) * n_ + y) * n_ + x) * columns_ + column;
  return element_bits_ == 32 ? static_cast<const uint32_t*>(sat_)[index]
                             : static_cast<const uint64_t*>(sat_)[index];
}

double RawRadianceTables::texel_value(uint32_t bin, uint32_t x, uint32_t y,
                                      uint32_t column) const noexcept {
  auto s = [&](uint32_t i, uint32_t j) -> uint64_t {  // S at corner (i, j), exclusive
    return (i == 0 || j == 0) ? 0 : sat_element(bin, i - 1, j - 1, column);
  };
  const uint64_t q = s(x + 1, y + 1) - s(x, y + 1) - s(x + 1, y) + s(x, y);
  return double(int64_t(q)) * unit(bin, column);
}

Status RawRadianceTables::check_contents() const noexcept {
  if (!is_open())
    return Status::error(ErrorCode::InvalidArgument, Check::None, "radiance tables not open");
  const uint32_t bins = bins_per_side_ * bins_per_side_;
  for (uint32_t b = 0; b < bins; ++b)
    for (uint32_t y = 0; y < n_; ++y)
      for (uint32_t x = 0; x < n_; ++x)
        for (uint32_t k = 0; k < columns_; ++k) {
          const uint64_t s11 = sat_element(b, x, y, k);
          const uint64_t s01 = x ? sat_element(b, x - 1, y, k) : 0;
          const uint64_t s10 = y ? sat_element(b, x, y - 1, k) : 0;
          const uint64_t s00 = x && y ? sat_element(b, x - 1, y - 1, k) : 0;
          // Non-negative texel and non-decreasing rows/columns, in exact integers.
          const bool ok = element_bits_ == 32
                              ? (int64_t(s11) - int64_t(s01) - int64_t(s10) + int64_t(s00) >= 0 &&
                                 s11 >= s01 && s11 >= s10)
                              : (s11 >= s01 && s11 >= s10 && s11 - s01 >= s10 - s00);
          if (!ok)
            return Status::error(ErrorCode::Malformed, Check::ValueRange,
                                 "radiance_tables %s: bin %u texel (%u, %u) cluster %u has a "
                                 "negative value (the SAT decreases)",
                                 radiance_kind_name(kind_), unsigned(b), unsigned(x), unsigned(y),
                                 unsigned(cluster_ids_[k]));
        }
  return {};
}

template <class E>
Status RawRadianceTables::query_impl(const Footprint& rect, const double h[3], int column,
                                     double* out) const noexcept {
  if (!is_open())
    return Status::error(ErrorCode::InvalidArgument, Check::None, "radiance tables not open");
  FootprintPlan plan;
  Status s = plan_footprint(rect, n_, &plan);
  if (!s.ok()) return s;
  BinWeights bw;
  s = radiance_bin_weights(bins_per_side_, h, &bw);
  if (!s.ok()) return s;

  const uint32_t first = column < 0 ? 0 : uint32_t(column);
  const uint32_t count = column < 0 ? columns_ : 1;
  const double size = double(n_);
  const PointLookup p11 = lookup(plan.rx1, plan.ry1, n_, columns_);
  const PointLookup p01 = lookup(plan.x0, plan.ry1, n_, columns_);
  const PointLookup p10 = lookup(plan.rx1, plan.y0, n_, columns_);
  const PointLookup p00 = lookup(plan.x0, plan.y0, n_, columns_);
  const bool cross_x = plan.qx > 0, cross_y = plan.qy > 0;
  PointLookup cx1{}, cx0{}, cy1{}, cy0{}, cxy{};
  if (cross_x) {
    cx1 = lookup(size, plan.ry1, n_, columns_);
    cx0 = lookup(size, plan.y0, n_, columns_);
  }
  if (cross_y) {
    cy1 = lookup(plan.rx1, size, n_, columns_);
    cy0 = lookup(plan.x0, size, n_, columns_);
  }
  if (cross_x && cross_y) cxy = lookup(size, size, n_, columns_);

  double acc[kMaxRadianceClusters + 1];
  uint64_t ip[kMaxRadianceClusters + 1];
  double fp[kMaxRadianceClusters + 1];
  for (uint32_t k = 0; k < count; ++k)
    acc[k] = 0.0;
  const uint64_t bin_stride = uint64_t(n_) * n_ * columns_;
  auto bracket = [&](const E* base, const PointLookup* points, const int* signs, int m,
                     double coefficient, double* total) {
    for (uint32_t k = 0; k < count; ++k) {
      ip[k] = 0;
      fp[k] = 0.0;
    }
    for (int t = 0; t < m; ++t)
      accumulate(base, points[t], first, count, signs[t], ip, fp);
    for (uint32_t k = 0; k < count; ++k)
      total[k] += coefficient * (double(int64_t(ip[k])) + fp[k]);
  };
  double bin_total[kMaxRadianceClusters + 1];
  for (uint32_t w = 0; w < bw.count; ++w) {
    const E* base = static_cast<const E*>(sat_) + uint64_t(bw.bin[w]) * bin_stride;
    for (uint32_t k = 0; k < count; ++k)
      bin_total[k] = 0.0;
    const PointLookup inner[4] = {p11, p01, p10, p00};
    const int inner_signs[4] = {+1, -1, -1, +1};
    bracket(base, inner, inner_signs, 4, 1.0, bin_total);
    const int pair_signs[2] = {+1, -1};
    if (cross_x) {
      const PointLookup pts[2] = {cx1, cx0};
      bracket(base, pts, pair_signs, 2, plan.qx, bin_total);
    }
    if (cross_y) {
      const PointLookup pts[2] = {cy1, cy0};
      bracket(base, pts, pair_signs, 2, plan.qy, bin_total);
    }
    if (cross_x && cross_y) {
      const int one[1] = {+1};
      bracket(base, &cxy, one, 1, plan.qx * plan.qy, bin_total);
    }
    const double* unit_row = units_ + uint64_t(bw.bin[w]) * columns_ + first;
    for (uint32_t k = 0; k < count; ++k)
      acc[k] += bw.weight[w] * unit_row[k] * bin_total[k];
  }
  if (column >= 0) {
    *out = acc[0];
  } else {
    for (uint32_t c = 0; c < cluster_count_; ++c)
      out[c] = 0.0;
    for (uint32_t k = 0; k < columns_; ++k)
      out[cluster_ids_[k]] = acc[k];
  }
  return {};
}

Status RawRadianceTables::query(const Footprint& rect, const double h[3], uint32_t cluster,
                                double* out) const noexcept {
  if (out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "query: null output");
  if (!is_open())
    return Status::error(ErrorCode::InvalidArgument, Check::None, "radiance tables not open");
  if (cluster >= cluster_count_)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "query: cluster %u out of range (the asset has %u)", unsigned(cluster),
                         unsigned(cluster_count_));
  const int column = column_of_[cluster];
  if (column < 0) {  // no stored table: the cluster's values are all zero
    FootprintPlan plan;
    Status s = plan_footprint(rect, n_, &plan);
    BinWeights bw;
    if (s.ok()) s = radiance_bin_weights(bins_per_side_, h, &bw);
    if (s.ok()) *out = 0.0;
    return s;
  }
  return element_bits_ == 32 ? query_impl<uint32_t>(rect, h, column, out)
                             : query_impl<uint64_t>(rect, h, column, out);
}

Status RawRadianceTables::query_all(const Footprint& rect, const double h[3],
                                    double* out) const noexcept {
  if (out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "query: null output");
  return element_bits_ == 32 ? query_impl<uint32_t>(rect, h, -1, out)
                             : query_impl<uint64_t>(rect, h, -1, out);
}

}  // namespace clothbake::reader

// Raw Integral-Radiance tables: opening with checks, exact fixed-point footprint queries
// (radiance_tables.hpp).
#include "formats/reader_raw/radiance_tables.hpp"

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

// One SAT point (x, y) in [0, N]^2 of a footprint plan: the element offsets (column 0) of
// S(i, j), S(i+1, j), S(i, j+1), S(i+1, j+1) with a mask that zeroes the corners on the i = 0 or
// j = 0 border (where the exclusive SAT is 0 and nothing is stored), the fractions a, b, and the
// bracket of the plan it belongs to with its sign.
struct PlanPoint {
  int64_t off[4];
  uint64_t mask[4];
  double a, b, ab;
  bool frac;
  bool negative;
  int bracket;
};

// The SAT points of a whole footprint plan (radiance_query.hpp): bracket 0 always (4 points),
// 1 when crossing tiles in x, 2 in y, 3 in both; F = sum_k coefficient[k] * bracket_k.
struct PlanPoints {
  PlanPoint p[9];
  int count = 0;
  double coefficient[4] = {1.0, 0.0, 0.0, 0.0};
  int brackets = 1;
};

inline void add_point(PlanPoints& pp, double x, double y, uint32_t n, uint32_t columns,
                      bool negative, int bracket) noexcept {
  const uint32_t i = x >= double(n) ? n - 1 : uint32_t(x);
  const uint32_t j = y >= double(n) ? n - 1 : uint32_t(y);
  PlanPoint& p = pp.p[pp.count++];
  p.a = x - double(i);
  p.b = y - double(j);
  p.ab = p.a * p.b;
  p.frac = p.a != 0.0 || p.b != 0.0;
  p.negative = negative;
  p.bracket = bracket;
  const uint32_t ci[4] = {i, i + 1, i, i + 1}, cj[4] = {j, j, j + 1, j + 1};
  for (int c = 0; c < 4; ++c) {
    const bool zero = ci[c] == 0 || cj[c] == 0;
    p.off[c] = zero ? 0 : (int64_t(cj[c] - 1) * int64_t(n) + int64_t(ci[c] - 1)) * int64_t(columns);
    p.mask[c] = zero ? 0 : ~uint64_t(0);
  }
}

inline PlanPoints plan_points(const FootprintPlan& plan, uint32_t n, uint32_t columns) noexcept {
  PlanPoints pp;
  const double size = double(n);
  add_point(pp, plan.rx1, plan.ry1, n, columns, false, 0);
  add_point(pp, plan.x0, plan.ry1, n, columns, true, 0);
  add_point(pp, plan.rx1, plan.y0, n, columns, true, 0);
  add_point(pp, plan.x0, plan.y0, n, columns, false, 0);
  if (plan.qx > 0) {
    add_point(pp, size, plan.ry1, n, columns, false, 1);
    add_point(pp, size, plan.y0, n, columns, true, 1);
    pp.coefficient[1] = plan.qx;
  }
  if (plan.qy > 0) {
    add_point(pp, plan.rx1, size, n, columns, false, 2);
    add_point(pp, plan.x0, size, n, columns, true, 2);
    pp.coefficient[2] = plan.qy;
  }
  if (plan.qx > 0 && plan.qy > 0) {
    add_point(pp, size, size, n, columns, false, 3);
    pp.coefficient[3] = plan.qx * plan.qy;
  }
  pp.brackets = 4;
  return pp;
}

// Adds sign * I(point) of one column (base at the column) to an integer part (wrapping uint64,
// exact: the true bracket values fit in int64) and a fractional part (double).
template <class E>
inline void add_point(const E* base, const PlanPoint& p, uint64_t& ip, double& fp) noexcept {
  const uint64_t s00 = uint64_t(base[p.off[0]]) & p.mask[0];
  ip += p.negative ? uint64_t(0) - s00 : s00;
  if (!p.frac) return;
  const uint64_t s10 = uint64_t(base[p.off[1]]) & p.mask[1];
  const uint64_t s01 = uint64_t(base[p.off[2]]) & p.mask[2];
  const uint64_t s11 = uint64_t(base[p.off[3]]) & p.mask[3];
  const double f = p.a * double(int64_t(s10 - s00)) + p.b * double(int64_t(s01 - s00)) +
                   p.ab * double(int64_t(s11 - s10 - s01 + s00));
  fp += p.negative ? -f : f;
}

// F of one column in integer steps (base at (bin, column)): brackets summed separately, each in
// exact integer arithmetic plus its fractional coverage, then weighted by its tile count. The
// points are ordered by bracket (plan_points), so each bracket is a contiguous range.
template <class E>
inline double evaluate_column(const E* base, const PlanPoints& pp) noexcept {
  uint64_t ip = 0;
  double fp = 0.0;
  for (int t = 0; t < 4; ++t)
    add_point(base, pp.p[t], ip, fp);
  double total = double(int64_t(ip)) + fp;
  for (int t = 4; t < pp.count;) {
    const int bracket = pp.p[t].bracket;
    ip = 0;
    fp = 0.0;
    for (; t < pp.count && pp.p[t].bracket == bracket; ++t)
      add_point(base, pp.p[t], ip, fp);
    total += pp.coefficient[bracket] * (double(int64_t(ip)) + fp);
  }
  return total;
}

// evaluate_column for `count` adjacent columns at once (base at column 0): the loops over
// columns read contiguous values (one cache line holds every cluster of a corner) and vectorise.
template <class E>
inline void evaluate_columns(const E* base, const PlanPoints& pp, uint32_t count,
                             double* result) noexcept {
  uint64_t ip[4][kMaxRadianceClusters + 1];
  double fp[4][kMaxRadianceClusters + 1];
  for (int b = 0; b < 4; ++b)
    for (uint32_t k = 0; k < count; ++k) {
      ip[b][k] = 0;
      fp[b][k] = 0.0;
    }
  for (int t = 0; t < pp.count; ++t) {
    const PlanPoint& p = pp.p[t];
    const E* c00 = base + p.off[0];
    uint64_t* ipb = ip[p.bracket];
    const uint64_t m00 = p.mask[0];
    if (p.negative)
      for (uint32_t k = 0; k < count; ++k)
        ipb[k] -= uint64_t(c00[k]) & m00;
    else
      for (uint32_t k = 0; k < count; ++k)
        ipb[k] += uint64_t(c00[k]) & m00;
    if (!p.frac) continue;
    const E* c10 = base + p.off[1];
    const E* c01 = base + p.off[2];
    const E* c11 = base + p.off[3];
    const uint64_t m10 = p.mask[1], m01 = p.mask[2], m11 = p.mask[3];
    const double sa = p.negative ? -p.a : p.a, sb = p.negative ? -p.b : p.b,
                 sab = p.negative ? -p.ab : p.ab;
    double* fpb = fp[p.bracket];
    for (uint32_t k = 0; k < count; ++k) {
      const uint64_t s00 = uint64_t(c00[k]) & m00, s10 = uint64_t(c10[k]) & m10,
                     s01 = uint64_t(c01[k]) & m01, s11 = uint64_t(c11[k]) & m11;
      fpb[k] += sa * double(int64_t(s10 - s00)) + sb * double(int64_t(s01 - s00)) +
                sab * double(int64_t(s11 - s10 - s01 + s00));
    }
  }
  for (uint32_t k = 0; k < count; ++k) {
    double total = double(int64_t(ip[0][k])) + fp[0][k];
    for (int b = 1; b < 4; ++b)
      if (pp.coefficient[b] != 0.0)
        total += pp.coefficient[b] * (double(int64_t(ip[b][k])) + fp[b][k]);
    result[k] = total;
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
  for (unsigned char b : info->reserved)
    if (b != 0)
      return Status::error(ErrorCode::Malformed, Check::Padding,
                           "radiance_tables %s (info): reserved bytes are not zero",
                           radiance_kind_name(kind));
  if (kind == RadianceTableKind::Gap && info->min_roughness != 0.0)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "radiance_tables gap (info): min_roughness %g must be 0",
                         info->min_roughness);
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

Status RawRadianceTables::texel_image(uint32_t bin, uint32_t cluster, float* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "radiance tables not open");
  if (bin >= bins_per_side_ * bins_per_side_ || cluster >= cluster_count_)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "radiance_tables %s: bin %u / cluster %u out of range (%u bins, %u "
                         "clusters)",
                         radiance_kind_name(kind_), unsigned(bin), unsigned(cluster),
                         unsigned(bins_per_side_ * bins_per_side_), unsigned(cluster_count_));
  const int column = column_of_[cluster];
  for (uint32_t y = 0; y < n_; ++y)
    for (uint32_t x = 0; x < n_; ++x)
      out[uint64_t(y) * n_ + x] =
          column < 0 ? 0.0f : float(texel_value(bin, x, y, uint32_t(column)));
  return {};
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

Status RawRadianceTables::check_against_labels(const uint8_t* labels) const noexcept {
  if (!is_open() || labels == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "radiance tables not open");
  const uint32_t bins = bins_per_side_ * bins_per_side_;
  for (uint32_t b = 0; b < bins; ++b)
    for (uint32_t y = 0; y < n_; ++y)
      for (uint32_t x = 0; x < n_; ++x) {
        const uint32_t label = labels[uint64_t(y) * n_ + x];
        for (uint32_t k = 0; k < columns_; ++k) {
          if (cluster_ids_[k] == label) continue;
          // The texel's integer, exact in wrapping arithmetic.
          const uint64_t q = sat_element(b, x, y, k) - (x ? sat_element(b, x - 1, y, k) : 0) -
                             (y ? sat_element(b, x, y - 1, k) : 0) +
                             (x && y ? sat_element(b, x - 1, y - 1, k) : 0);
          const uint64_t mask = element_bits_ == 32 ? 0xffffffffull : ~0ull;
          if ((q & mask) != 0)
            return Status::error(ErrorCode::Malformed, Check::CrossSection,
                                 "radiance_tables %s: bin %u texel (%u, %u) has a value in the "
                                 "table of cluster %u but the label map puts it in cluster %u",
                                 radiance_kind_name(kind_), unsigned(b), unsigned(x), unsigned(y),
                                 unsigned(cluster_ids_[k]), unsigned(label));
        }
      }
  return {};
}

template <class E>
bool RawRadianceTables::query_impl(const Footprint& rect, const double h[3], int column,
                                   double* out) const noexcept {
  FootprintPlan plan;
  BinWeights bw;
  if (!make_footprint_plan(rect, n_, &plan) || !make_bin_weights(bins_per_side_, h, &bw))
    return false;
  const PlanPoints points = plan_points(plan, n_, columns_);
  const uint64_t bin_stride = uint64_t(n_) * n_ * columns_;
  const E* sat = static_cast<const E*>(sat_);
  if (column >= 0) {
    double f = 0.0;
    for (uint32_t w = 0; w < bw.count; ++w) {
      const E* base = sat + uint64_t(bw.bin[w]) * bin_stride + uint32_t(column);
      f += bw.weight[w] * units_[uint64_t(bw.bin[w]) * columns_ + uint32_t(column)] *
           evaluate_column(base, points);
    }
    *out = f;
    return true;
  }
  double acc[kMaxRadianceClusters + 1], bin_value[kMaxRadianceClusters + 1];
  for (uint32_t k = 0; k < columns_; ++k)
    acc[k] = 0.0;
  for (uint32_t w = 0; w < bw.count; ++w) {
    evaluate_columns(sat + uint64_t(bw.bin[w]) * bin_stride, points, columns_, bin_value);
    const double* unit_row = units_ + uint64_t(bw.bin[w]) * columns_;
    for (uint32_t k = 0; k < columns_; ++k)
      acc[k] += bw.weight[w] * unit_row[k] * bin_value[k];
  }
  for (uint32_t c = 0; c < cluster_count_; ++c)
    out[c] = 0.0;
  for (uint32_t k = 0; k < columns_; ++k)
    out[cluster_ids_[k]] = acc[k];
  return true;
}

bool RawRadianceTables::try_query(const Footprint& rect, const double h[3], uint32_t cluster,
                                  double* out) const noexcept {
  if (out == nullptr || !is_open() || cluster >= cluster_count_) return false;
  const int column = column_of_[cluster];
  if (column < 0) {  // no stored table: the cluster's values are all zero
    FootprintPlan plan;
    BinWeights bw;
    if (!make_footprint_plan(rect, n_, &plan) || !make_bin_weights(bins_per_side_, h, &bw))
      return false;
    *out = 0.0;
    return true;
  }
  return element_bits_ == 32 ? query_impl<uint32_t>(rect, h, column, out)
                             : query_impl<uint64_t>(rect, h, column, out);
}

bool RawRadianceTables::try_query_all(const Footprint& rect, const double h[3],
                                      double* out) const noexcept {
  if (out == nullptr || !is_open()) return false;
  return element_bits_ == 32 ? query_impl<uint32_t>(rect, h, -1, out)
                             : query_impl<uint64_t>(rect, h, -1, out);
}

}  // namespace clothbake::reader

// Footprint plans and half-vector bin weights shared by every table representation
// (radiance_query.hpp).
#include "formats/reader/radiance_query.hpp"

#include <cmath>

#include "model/directions.hpp"

namespace clothbake::reader {

namespace {

constexpr double kMaxCoordinate = 1099511627776.0;  // 2^40 texels: keeps a fractional part

// [lo, hi) -> lo in [0, size), the remainder r of hi in [0, size] and whole tiles q, by a shift of
// whole tiles (the table is periodic).
inline void reduce_interval(double lo, double hi, double size, double inv_size, double* lo_out,
                            double* r_out, double* q_out) noexcept {
  double k = std::floor(lo * inv_size);
  double l = lo - k * size;
  if (l < 0) {  // inv_size is rounded: fix the tile index in either direction
    l += size;
    k -= 1;
  }
  if (l >= size) {
    l -= size;
    k += 1;
  }
  if (l < 0) l = 0;
  double h = hi - k * size;
  if (h < l) h = l;
  double q = std::floor(h * inv_size);
  double r = h - q * size;
  if (r < 0) {
    r += size;
    q -= 1;
  }
  if (r > size) {
    r -= size;
    q += 1;
  }
  if (r < 0) r = 0;
  *lo_out = l;
  *r_out = r;
  *q_out = q;
}

}  // namespace

bool make_footprint_plan(const Footprint& rect, uint32_t n, FootprintPlan* out) noexcept {
  const double x0 = rect.x0, y0 = rect.y0, x1 = rect.x1, y1 = rect.y1;
  const double size = double(n);
  // Every comparison is false for NaN, so NaN corners fail here too.
  if (!(n > 0 && x1 >= x0 && y1 >= y0 && std::abs(x0) <= kMaxCoordinate &&
        std::abs(x1) <= kMaxCoordinate && std::abs(y0) <= kMaxCoordinate &&
        std::abs(y1) <= kMaxCoordinate && (x1 - x0) <= kMaxFootprintTiles * size &&
        (y1 - y0) <= kMaxFootprintTiles * size))
    return false;
  const double inv = 1.0 / size;
  reduce_interval(x0, x1, size, inv, &out->x0, &out->rx1, &out->qx);
  reduce_interval(y0, y1, size, inv, &out->y0, &out->ry1, &out->qy);
  return true;
}

Status plan_footprint(const Footprint& rect, uint32_t n, FootprintPlan* out) noexcept {
  if (out == nullptr || n == 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "footprint: no table resolution");
  if (make_footprint_plan(rect, n, out)) return {};
  const double x0 = rect.x0, y0 = rect.y0, x1 = rect.x1, y1 = rect.y1;
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: corners must be finite");
  if (x1 < x0 || y1 < y0)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: [%g, %g) x [%g, %g) has x1 < x0 or y1 < y0", x0, x1, y0, y1);
  if ((x1 - x0) > kMaxFootprintTiles * double(n) || (y1 - y0) > kMaxFootprintTiles * double(n))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: wider than 2^24 tiles");
  return Status::error(ErrorCode::InvalidArgument, Check::None,
                       "footprint: corners beyond 2^40 texels");
}

bool make_bin_weights(uint32_t bins_per_side, const double h[3], BinWeights* out) noexcept {
  if (bins_per_side == 1) {
    out->count = 1;
    out->bin[0] = 0;
    out->weight[0] = 1.0;
    return true;
  }
  if (bins_per_side == 0 || h == nullptr) return false;
  const double len2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
  if (!(len2 > 0.0) || !(len2 < 1e300)) return false;  // zero, NaN or Inf
  const model::DirectionGrid<double> grid{int(bins_per_side), 0.0};
  const model::BinBilinear<double> b =
      grid.bilinear_fast(model::fold_to_upper_hemisphere(model::Vec3d(h[0], h[1], h[2])));
  uint32_t count = 0;
  for (int k = 0; k < 4; ++k) {
    if (!(b.weight[k] > 0.0)) continue;
    const uint32_t bin = uint32_t(b.index[k]);
    uint32_t m = 0;
    while (m < count && out->bin[m] != bin)
      ++m;
    if (m == count) {
      out->bin[m] = bin;
      out->weight[m] = 0.0;
      ++count;
    }
    out->weight[m] += b.weight[k];
  }
  out->count = count;
  return true;
}

Status radiance_bin_weights(uint32_t bins_per_side, const double h[3], BinWeights* out) noexcept {
  if (out == nullptr || bins_per_side == 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "bin weights: no bin grid");
  if (make_bin_weights(bins_per_side, h, out)) return {};
  if (h == nullptr || !std::isfinite(h[0]) || !std::isfinite(h[1]) || !std::isfinite(h[2]))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "half vector must have finite components");
  return Status::error(ErrorCode::InvalidArgument, Check::None,
                       "half vector must not be the zero vector");
}

#ifndef CLOTHBAKE_SINGLE_FILE
Status RadianceTables::query(const Footprint& rect, const double h[3], uint32_t cluster,
                             double* out) const noexcept {
  if (try_query(rect, h, cluster, out)) return {};
  return diagnose(rect, h, &cluster, out);
}

Status RadianceTables::query_all(const Footprint& rect, const double h[3],
                                 double* out) const noexcept {
  if (try_query_all(rect, h, out)) return {};
  return diagnose(rect, h, nullptr, out);
}

Status RadianceTables::diagnose(const Footprint& rect, const double h[3], const uint32_t* cluster,
                                const double* out) const noexcept {
  if (resolution() == 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "radiance tables not open");
  if (out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "query: null output");
  if (cluster != nullptr && *cluster >= cluster_count())
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "query: cluster %u out of range (the asset has %u)", unsigned(*cluster),
                         unsigned(cluster_count()));
  FootprintPlan plan;
  Status s = plan_footprint(rect, resolution(), &plan);
  if (!s.ok()) return s;
  BinWeights w;
  s = radiance_bin_weights(bins_per_side(), h, &w);
  if (!s.ok()) return s;
  if (!covers_bins(h))
    return Status::error(ErrorCode::OutOfPlan, Check::None,
                         "query: a half-vector bin of h was left out of this scene-planned asset "
                         "(bin_map instance 0)");
  return Status::error(ErrorCode::InvalidArgument, Check::None, "query: invalid arguments");
}
#endif

}  // namespace clothbake::reader

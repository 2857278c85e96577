// Footprint plans and half-vector bin weights shared by every table representation
// (radiance_query.hpp).
#include "formats/reader/radiance_query.hpp"

#include <cmath>

#include "model/directions.hpp"

namespace clothbake::reader {

Status plan_footprint(const Footprint& rect, uint32_t n, FootprintPlan* out) noexcept {
  if (out == nullptr || n == 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "footprint: no table resolution");
  const double x0 = rect.x0, y0 = rect.y0, x1 = rect.x1, y1 = rect.y1;
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: corners must be finite");
  if (x1 < x0 || y1 < y0)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: [%g, %g) x [%g, %g) has x1 < x0 or y1 < y0", x0, x1, y0, y1);
  const double size = double(n);
  const double limit = 1099511627776.0;  // 2^40 texels: keeps a fractional part in a double
  if (std::abs(x0) > limit || std::abs(x1) > limit || std::abs(y0) > limit || std::abs(y1) > limit)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: corners beyond 2^40 texels");
  if ((x1 - x0) > kMaxFootprintTiles * size || (y1 - y0) > kMaxFootprintTiles * size)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "footprint: wider than 2^24 tiles");
  // Shift by whole tiles so that (x0, y0) lies in [0, N): the table is periodic.
  auto reduce = [size](double lo, double hi, double* lo_out, double* r_out, double* q_out) {
    double k = std::floor(lo / size);
    double l = lo - k * size;
    if (l >= size) {
      l -= size;
      k += 1;
    }
    if (l < 0) l = 0;
    double h = hi - k * size;
    if (h < l) h = l;
    double q = std::floor(h / size);
    double r = h - q * size;
    if (r < 0) r = 0;
    if (r > size) r = size;
    *lo_out = l;
    *r_out = r;
    *q_out = q;
  };
  FootprintPlan plan;
  reduce(x0, x1, &plan.x0, &plan.rx1, &plan.qx);
  reduce(y0, y1, &plan.y0, &plan.ry1, &plan.qy);
  *out = plan;
  return {};
}

Status radiance_bin_weights(uint32_t bins_per_side, const double h[3], BinWeights* out) noexcept {
  if (out == nullptr || bins_per_side == 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "bin weights: no bin grid");
  BinWeights w;
  if (bins_per_side == 1) {
    w.count = 1;
    w.bin[0] = 0;
    w.weight[0] = 1.0;
    *out = w;
    return {};
  }
  if (h == nullptr || !std::isfinite(h[0]) || !std::isfinite(h[1]) || !std::isfinite(h[2]))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "half vector must have finite components");
  model::Vec3d v(h[0], h[1], h[2]);
  if (!(model::dot(v, v) > 0.0))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "half vector must not be the zero vector");
  const model::DirectionGrid<double> grid{int(bins_per_side), 0.0};
  const model::BinBilinear<double> b = grid.bilinear(model::fold_to_upper_hemisphere(v));
  for (int k = 0; k < 4; ++k) {
    if (!(b.weight[k] > 0.0)) continue;
    uint32_t bin = uint32_t(b.index[k]);
    uint32_t m = 0;
    while (m < w.count && w.bin[m] != bin)
      ++m;
    if (m == w.count) {
      w.bin[m] = bin;
      w.weight[m] = 0.0;
      ++w.count;
    }
    w.weight[m] += b.weight[k];
  }
  *out = w;
  return {};
}

}  // namespace clothbake::reader

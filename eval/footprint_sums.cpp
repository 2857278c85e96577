// Footprint integrals of the evaluator's per-texel sums (footprint_sums.hpp).
#include "eval/footprint_sums.hpp"

namespace clothbake::eval {

void FootprintSums::add_prefix(double x, double y, double weight, uint32_t first, uint32_t count,
                               double* out) const noexcept {
  // The prefix integral of piecewise-constant texels is the bilinear interpolation of the integer
  // corners' prefix sums (docs/evaluator.md, "Footprint sums").
  uint32_t i = uint32_t(x), j = uint32_t(y);
  if (i > n_) i = n_;
  if (j > n_) j = n_;
  const double fx = i < n_ ? x - double(i) : 0.0, fy = j < n_ ? y - double(j) : 0.0;
  const uint32_t i1 = i < n_ ? i + 1 : n_, j1 = j < n_ ? j + 1 : n_;
  const double w00 = weight * (1.0 - fx) * (1.0 - fy), w10 = weight * fx * (1.0 - fy),
               w01 = weight * (1.0 - fx) * fy, w11 = weight * fx * fy;
  const double* p00 = point(i, j) + first;
  for (uint32_t c = 0; c < count; ++c)
    out[c] += w00 * p00[c];
  if (w10 != 0.0) {
    const double* p = point(i1, j) + first;
    for (uint32_t c = 0; c < count; ++c)
      out[c] += w10 * p[c];
  }
  if (w01 != 0.0) {
    const double* p = point(i, j1) + first;
    for (uint32_t c = 0; c < count; ++c)
      out[c] += w01 * p[c];
  }
  if (w11 != 0.0) {
    const double* p = point(i1, j1) + first;
    for (uint32_t c = 0; c < count; ++c)
      out[c] += w11 * p[c];
  }
}

void FootprintSums::integral(const reader::FootprintPlan& plan, uint32_t first, uint32_t count,
                             double* out) const noexcept {
  for (uint32_t c = 0; c < count; ++c)
    out[c] = 0.0;
  if (n_ == 0) return;
  const double n = double(n_);
  // F = [I(rx1, ry1) - I(x0, ry1) - I(rx1, y0) + I(x0, y0)] + qx [I(N, ry1) - I(N, y0)]
  //   + qy [I(rx1, N) - I(x0, N)] + qx qy I(N, N)          (reader::FootprintPlan)
  add_prefix(plan.rx1, plan.ry1, 1.0, first, count, out);
  add_prefix(plan.x0, plan.ry1, -1.0, first, count, out);
  add_prefix(plan.rx1, plan.y0, -1.0, first, count, out);
  add_prefix(plan.x0, plan.y0, 1.0, first, count, out);
  if (plan.qx > 0) {
    add_prefix(n, plan.ry1, plan.qx, first, count, out);
    add_prefix(n, plan.y0, -plan.qx, first, count, out);
  }
  if (plan.qy > 0) {
    add_prefix(plan.rx1, n, plan.qy, first, count, out);
    add_prefix(plan.x0, n, -plan.qy, first, count, out);
  }
  if (plan.qx > 0 && plan.qy > 0) add_prefix(n, n, plan.qx * plan.qy, first, count, out);
}

}  // namespace clothbake::eval

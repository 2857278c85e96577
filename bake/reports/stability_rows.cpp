// The accumulator of `report stability` (stability_rows.hpp).
#include "bake/reports/stability_rows.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>

namespace clothbake::reports::stability {

std::string num(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{:g}", v);
}

Vec3d direction(double cos_theta, double phi) {
  const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

void Report::add_row(StabilityRow row, const std::vector<Sample>& samples) {
  for (const Sample& s : samples) {
    ++row.n_queries;
    if (!std::isfinite(s.q)) {
      ++row.n_nonfinite;
      continue;
    }
    if (s.nonnegative && s.q < 0) ++row.n_negative;
    if (std::isnan(s.d)) continue;
    const double e = std::abs(s.q - s.d);
    const double rel = e / std::max(std::abs(s.d), row.rel_floor);
    // NaN errors (a non-finite direct value) count as failures through the comparison below.
    if (!(e <= row.max_abs_error)) row.max_abs_error = std::isnan(e) ? kInf : e;
    if (!(rel <= row.max_rel_error)) row.max_rel_error = std::isnan(rel) ? kInf : rel;
  }
  row.pass = row.n_nonfinite == 0 && row.n_negative == 0 &&
             (!row.tolerance || row.max_rel_error <= *row.tolerance);
  rows.push_back(std::move(row));
}

void Report::add_relative_row(StabilityRow row, const std::vector<double>& errors) {
  for (double e : errors) {
    if (!std::isfinite(e)) {
      ++row.n_nonfinite;
      continue;
    }
    row.max_rel_error = std::max(row.max_rel_error, e);
  }
  row.max_abs_error = row.max_rel_error;
  row.pass = row.n_nonfinite == 0 && (!row.tolerance || row.max_rel_error <= *row.tolerance);
  rows.push_back(std::move(row));
}

void Report::add(const Quantity& q) {
  auto axis = [&](const char* name, const std::vector<double>& values, int Sample::*field) {
    std::map<int, std::vector<Sample>> groups;
    for (const Sample& s : q.samples)
      if (s.*field >= 0) groups[s.*field].push_back(s);
    for (auto& [index, samples] : groups) {
      StabilityRow row = base(q);
      row.parameter = fmt::format("{}={}", name, num(values[std::size_t(index)]));
      add_row(std::move(row), samples);
    }
    return !groups.empty();
  };
  bool any = axis("roughness", kRoughness, &Sample::roughness);
  any |= axis("cos_theta", kCosines, &Sample::cosine);
  any |= axis("thickness", kThickness, &Sample::thickness);
  if (!any) {
    StabilityRow row = base(q);
    // std::string(1, '-'), not "-": GCC 12 at -O3 warns on assigning the literal here
    // (-Wrestrict, a false positive of its inlined string copy).
    row.parameter = std::string(1, '-');
    add_row(std::move(row), q.samples);
  }
}

StabilityRow Report::base(const Quantity& q) {
  StabilityRow row;
  row.case_name = q.case_name;
  row.quantity = q.quantity;
  row.direct = q.direct;
  row.rel_floor = q.rel_floor;
  row.tolerance = q.tolerance;
  return row;
}

}  // namespace clothbake::reports::stability

#include "bake/inputs/map_stats.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace clothbake::inputs {
namespace {

template <class Get>
ChannelStats stats_of(std::size_t count, Get get) {
  ChannelStats s;
  if (count == 0) return s;
  // Two passes (mean, then squared deviations): no cancellation for maps with a large offset.
  double sum = 0, lo = get(0), hi = get(0);
  for (std::size_t i = 0; i < count; ++i) {
    double v = get(i);
    sum += v;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  s.mean = sum / double(count);
  double sq = 0;
  for (std::size_t i = 0; i < count; ++i) {
    double d = get(i) - s.mean;
    sq += d * d;
  }
  s.stddev = std::sqrt(sq / double(count));
  s.min = lo;
  s.max = hi;
  return s;
}

constexpr double kDegrees = 180.0 / std::numbers::pi;

}  // namespace

ChannelStats channel_stats(const std::vector<float>& values) {
  return stats_of(values.size(), [&](std::size_t i) { return double(values[i]); });
}

ChannelStats channel_stats(const std::vector<Vec3f>& values, int c) {
  return stats_of(values.size(), [&](std::size_t i) { return double(values[i][c]); });
}

TangentStats tangent_stats(const std::vector<Vec3f>& tangents) {
  TangentStats s;
  if (tangents.empty()) return s;
  double abs_z = 0, elevation = 0, c2 = 0, s2 = 0;
  std::size_t along_x = 0, along_y = 0;
  for (const auto& t : tangents) {
    double z = std::min(1.0, std::abs(double(t[2])));
    abs_z += z;
    elevation += std::asin(z);
    double ax = std::abs(t[0]), ay = std::abs(t[1]);
    if (ax > ay) ++along_x;
    if (ay > ax) ++along_y;
    // (cos 2phi, sin 2phi) * r^2 = (x^2 - y^2, 2xy): axial, and weighted by the in-plane length
    // squared so that nearly vertical fibres (whose phi is noise) count little.
    c2 += double(t[0]) * t[0] - double(t[1]) * t[1];
    s2 += 2.0 * double(t[0]) * t[1];
  }
  double n = double(tangents.size());
  s.mean_abs_z = abs_z / n;
  s.mean_elevation_deg = elevation / n * kDegrees;
  s.fraction_along_x = double(along_x) / n;
  s.fraction_along_y = double(along_y) / n;
  s.axial_concentration = std::hypot(c2, s2) / n;
  double axis = 0.5 * std::atan2(s2, c2) * kDegrees;  // (-90, 90]
  if (axis <= -90.0) axis += 180.0;
  s.mean_axis_deg = axis;
  return s;
}

MapStats map_stats(const FabricMaps& maps) {
  MapStats s;
  s.resolution = maps.resolution;
  s.height = channel_stats(maps.height);
  s.gap = channel_stats(maps.gap);
  for (int c = 0; c < 3; ++c) {
    s.tangent[c] = channel_stats(maps.tangent, c);
    s.normal[c] = channel_stats(maps.normal, c);
    s.albedo[c] = channel_stats(maps.albedo, c);
  }
  std::size_t gaps = 0;
  for (float g : maps.gap)
    gaps += g < 0.5f ? 1 : 0;
  s.gap_fraction = maps.gap.empty() ? 0.0 : double(gaps) / double(maps.gap.size());
  s.tangent_directions = tangent_stats(maps.tangent);
  double tilt = 0;
  for (const auto& nrm : maps.normal)
    tilt += std::acos(std::clamp(double(nrm[2]), -1.0, 1.0));
  s.mean_normal_tilt_deg = maps.normal.empty() ? 0.0 : tilt / double(maps.normal.size()) * kDegrees;
  for (uint16_t id : maps.yarn_id) {
    if (id >= s.yarn_texels.size()) s.yarn_texels.resize(std::size_t(id) + 1, 0);
    ++s.yarn_texels[id];
  }
  return s;
}

}  // namespace clothbake::inputs

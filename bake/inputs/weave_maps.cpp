// Procedural weave feature maps (docs/weaves.md, "Geometry model").
#include "bake/inputs/weave_maps.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "common/error.hpp"

namespace clothbake::weave {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Largest physical value accepted for a spacing or a thickness (1 m): beyond it the input is
// certainly a unit mistake, and bounding it keeps every product finite.
constexpr double kMaxLengthMm = 1000.0;
// The cross-section is an ellipse up to |r| = kRimStart (r = lateral offset / half-width), then
// its tangent line out to the edge: the slope stays bounded (about 10 b / a) instead of
// diverging at the silhouette, so no shading normal is horizontal (docs/weaves.md).
constexpr double kRimStart = 0.995;

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

void check_geometry(const YarnGeometry& g, const std::string& where, const std::string& name) {
  auto bad = [&](const std::string& field, double value, const std::string& range) {
    throw_input_error(where + ": " + name + "." + field + " = " + number(value) + " is outside " +
                      range);
  };
  if (!std::isfinite(g.spacing_mm) || g.spacing_mm <= 0 || g.spacing_mm > kMaxLengthMm)
    bad("spacing_mm", g.spacing_mm, "(0, " + number(kMaxLengthMm) + "] mm");
  if (!std::isfinite(g.width) || g.width <= 0 || g.width > 1) bad("width", g.width, "(0, 1]");
  if (!std::isfinite(g.height_mm) || g.height_mm <= 0 || g.height_mm > kMaxLengthMm)
    bad("height_mm", g.height_mm, "(0, " + number(kMaxLengthMm) + "] mm");
  if (!std::isfinite(g.twist_deg) || g.twist_deg <= -90 || g.twist_deg >= 90)
    bad("twist_deg", g.twist_deg, "(-90, 90) degrees");
}

void check_colors(const std::vector<Rgb>& colors, int expected, const std::string& where,
                  const std::string& name, const std::string& thread) {
  if (colors.empty()) return;
  if (colors.size() != std::size_t(expected))
    throw_input_error(where + ": " + name + " has " + std::to_string(colors.size()) +
                      " entries, expected " + std::to_string(expected) + " (one per " + thread +
                      ") or none");
  for (std::size_t i = 0; i < colors.size(); ++i)
    for (double c : colors[i])
      if (!std::isfinite(c) || c < 0 || c > 1)
        throw_input_error(where + ": " + name + " of " + thread + " " + std::to_string(i + 1) +
                          " has a component " + number(c) + " outside [0, 1] (linear RGB)");
}

std::vector<WeaveSurface::Thread> layout(const YarnGeometry& common,
                                         const std::vector<YarnGeometry>& per_thread,
                                         const std::vector<Rgb>& colors, int count) {
  std::vector<WeaveSurface::Thread> threads(static_cast<std::size_t>(count));
  double start = 0;
  for (int i = 0; i < count; ++i) {
    const YarnGeometry& g = per_thread.empty() ? common : per_thread[std::size_t(i)];
    WeaveSurface::Thread& t = threads[std::size_t(i)];
    t.start = start;
    t.spacing = g.spacing_mm;
    t.centre = start + 0.5 * g.spacing_mm;
    t.half_width = 0.5 * g.width * g.spacing_mm;
    t.half_height = 0.5 * g.height_mm;
    t.cos_twist = std::cos(g.twist_deg * kPi / 180.0);
    t.sin_twist = std::sin(g.twist_deg * kPi / 180.0);
    if (!colors.empty()) t.color = colors[std::size_t(i)];
    start += g.spacing_mm;
  }
  return threads;
}

// Top of an elliptical cross-section of half-width a and half-height b at lateral offset d
// (|d| < a), with the rim replaced by the tangent line at kRimStart; returns the height above
// the centre line and its derivative with respect to d.
void cross_section(double d, double a, double b, double& height, double& slope) {
  const double r = d / a;
  const double ar = std::fabs(r);
  if (ar <= kRimStart) {
    const double s = std::sqrt(1.0 - r * r);
    height = b * s;
    slope = -b * r / (a * s);
    return;
  }
  const double s0 = std::sqrt(1.0 - kRimStart * kRimStart);
  const double slope0 = b * kRimStart / (a * s0);  // magnitude of the slope at the rim start
  height = b * s0 - slope0 * (ar - kRimStart) * a;
  slope = r > 0 ? -slope0 : slope0;
}

model::Vec3d twisted(const model::Vec3d& axis, const model::Vec3d& normal, double cos_twist,
                     double sin_twist) {
  // Clockwise about the normal seen from above for positive twist: axis x normal points to the
  // right of the axis.
  return model::normalize(axis * cos_twist + model::cross(axis, normal) * sin_twist);
}

// Distance (mm) from an uncovered coordinate to the nearest yarn edge of one system: the owner's
// or that of its neighbour on the side of the offset; `nearest` receives that thread.
double distance_to_nearest_yarn(const std::vector<WeaveSurface::Thread>& threads,
                                const WeaveSurface::AxisPoint& p, int& nearest) {
  const int n = int(threads.size());
  const WeaveSurface::Thread& own = threads[std::size_t(p.owner)];
  const int side_index = p.offset > 0 ? (p.owner + 1) % n : (p.owner + n - 1) % n;
  const WeaveSurface::Thread& side = threads[std::size_t(side_index)];
  const double to_own = std::fabs(p.offset) - own.half_width;
  const double to_side =
      0.5 * own.spacing + 0.5 * side.spacing - std::fabs(p.offset) - side.half_width;
  nearest = to_own <= to_side ? p.owner : side_index;
  return std::min(to_own, to_side);
}

}  // namespace

void validate_weave_spec(const WeaveSpec& spec, const std::string& where) {
  check_weavable(spec.matrix, where);
  check_geometry(spec.warp, where, "warp");
  check_geometry(spec.weft, where, "weft");
  const int ends = spec.matrix.ends, picks = spec.matrix.picks;
  check_colors(spec.end_colors, ends, where, "end_colors", "end");
  check_colors(spec.pick_colors, picks, where, "pick_colors", "pick");
  auto check_per_thread = [&](const std::vector<YarnGeometry>& list, int expected,
                              const std::string& name, const std::string& thread) {
    if (list.empty()) return;
    if (list.size() != std::size_t(expected))
      throw_input_error(where + ": " + name + " has " + std::to_string(list.size()) +
                        " entries, expected " + std::to_string(expected) + " (one per " + thread +
                        ") or none");
    for (std::size_t i = 0; i < list.size(); ++i)
      check_geometry(list[i], where, thread + " " + std::to_string(i + 1) + " geometry");
  };
  check_per_thread(spec.end_geometry, ends, "end_geometry", "end");
  check_per_thread(spec.pick_geometry, picks, "pick_geometry", "pick");
}

WeaveSpec repeat_weave_spec(const WeaveSpec& spec, int ends_times, int picks_times,
                            const std::string& where) {
  WeaveSpec out = spec;
  const WeaveMatrix& m = spec.matrix;
  out.matrix = make_matrix(m.picks * picks_times, m.ends * ends_times, where);  // size checked
  for (int p = 0; p < out.matrix.picks; ++p)
    for (int e = 0; e < out.matrix.ends; ++e)
      out.matrix.set(p, e, m.warp_up(p % m.picks, e % m.ends));
  auto repeat = [](auto list, int times) {
    auto once = list;
    for (int k = 1; k < times; ++k)
      list.insert(list.end(), once.begin(), once.end());
    return list;
  };
  out.end_colors = repeat(spec.end_colors, ends_times);
  out.pick_colors = repeat(spec.pick_colors, picks_times);
  out.end_geometry = repeat(spec.end_geometry, ends_times);
  out.pick_geometry = repeat(spec.pick_geometry, picks_times);
  return out;
}

TileSize weave_tile_size(const WeaveSpec& spec) {
  // Summed in long double and rounded once: eight ends of 0.4 mm are 3.2 mm, not the
  // 3.1999999999999997 of a running double sum (which a written fabric.toml would then show).
  long double width = 0, height = 0;
  for (int e = 0; e < spec.matrix.ends; ++e)
    width += spec.end_geometry.empty() ? spec.warp.spacing_mm
                                       : spec.end_geometry[std::size_t(e)].spacing_mm;
  for (int p = 0; p < spec.matrix.picks; ++p)
    height += spec.pick_geometry.empty() ? spec.weft.spacing_mm
                                         : spec.pick_geometry[std::size_t(p)].spacing_mm;
  TileSize tile;
  tile.width_mm = double(width);
  tile.height_mm = double(height);
  tile.height_unit_mm = tile.width_mm;
  return tile;
}

WeaveSurface::WeaveSurface(const WeaveSpec& spec, const std::string& where) {
  validate_weave_spec(spec, where);
  matrix_ = spec.matrix;
  ends_ = layout(spec.warp, spec.end_geometry, spec.end_colors, matrix_.ends);
  picks_ = layout(spec.weft, spec.pick_geometry, spec.pick_colors, matrix_.picks);
  tile_ = weave_tile_size(spec);
  double max_end_b = 0, max_pick_b = 0;
  for (const Thread& t : ends_)
    max_end_b = std::max(max_end_b, t.half_height);
  for (const Thread& t : picks_)
    max_pick_b = std::max(max_pick_b, t.half_height);
  // Every centre line stays within +-(largest crossing half-thickness) and every visible top is
  // at or above its centre line, so the underside of the thickest crossing is below all of them.
  floor_mm_ = -(max_end_b + max_pick_b);
}

WeaveSurface::AxisPoint WeaveSurface::locate(const std::vector<Thread>& threads, double length,
                                             double coord) {
  AxisPoint out;
  const int n = int(threads.size());
  // Owner: the last thread whose band starts at or before coord.
  auto owner_it = std::upper_bound(threads.begin(), threads.end(), coord,
                                   [](double c, const Thread& t) { return c < t.start; });
  out.owner = owner_it == threads.begin() ? 0 : int(owner_it - threads.begin()) - 1;
  out.offset = coord - threads[std::size_t(out.owner)].centre;
  // Crossings: the centres either side of coord, periodically.
  auto centre_it = std::upper_bound(threads.begin(), threads.end(), coord,
                                    [](double c, const Thread& t) { return c < t.centre; });
  double left = 0, right = 0;
  if (centre_it == threads.begin()) {
    out.before = n - 1;
    out.after = 0;
    left = threads.back().centre - length;
    right = threads.front().centre;
  } else {
    out.before = int(centre_it - threads.begin()) - 1;
    out.after = out.before + 1 == n ? 0 : out.before + 1;
    left = threads[std::size_t(out.before)].centre;
    right =
        out.after == 0 ? threads.front().centre + length : threads[std::size_t(out.after)].centre;
  }
  const double span = right - left;
  const double t = (coord - left) / span;
  out.ease = 0.5 * (1.0 - std::cos(kPi * t));
  out.ease_slope = 0.5 * kPi * std::sin(kPi * t) / span;
  return out;
}

WeaveSample WeaveSurface::evaluate(const AxisPoint& x, const AxisPoint& y) const {
  const double W = tile_.width_mm, H = tile_.height_mm, unit = tile_.height_unit_mm;
  WeaveSample out;
  bool have = false;
  double best_z = 0, best_dx = 0, best_dy = 0;

  // Warp end owning x: runs along y, crimps over/under the picks at y.before / y.after.
  const Thread& end = ends_[std::size_t(x.owner)];
  if (std::fabs(x.offset) < end.half_width) {
    const double b0 = picks_[std::size_t(y.before)].half_height;
    const double b1 = picks_[std::size_t(y.after)].half_height;
    const double t0 = matrix_.warp_up(y.before, x.owner) ? b0 : -b0;
    const double t1 = matrix_.warp_up(y.after, x.owner) ? b1 : -b1;
    double top = 0, top_slope = 0;
    cross_section(x.offset, end.half_width, end.half_height, top, top_slope);
    best_z = t0 + (t1 - t0) * y.ease + top;
    best_dx = top_slope;
    best_dy = (t1 - t0) * y.ease_slope;
    out.yarn_id = 0;
    out.thread = x.owner;
    have = true;
  }
  // Weft pick owning y: runs along x, crimps under/over the ends at x.before / x.after.
  const Thread& pick = picks_[std::size_t(y.owner)];
  if (std::fabs(y.offset) < pick.half_width) {
    const double b0 = ends_[std::size_t(x.before)].half_height;
    const double b1 = ends_[std::size_t(x.after)].half_height;
    const double t0 = matrix_.warp_up(y.owner, x.before) ? -b0 : b0;
    const double t1 = matrix_.warp_up(y.owner, x.after) ? -b1 : b1;
    double top = 0, top_slope = 0;
    cross_section(y.offset, pick.half_width, pick.half_height, top, top_slope);
    const double z = t0 + (t1 - t0) * x.ease + top;
    if (!have || z > best_z) {
      best_z = z;
      best_dx = (t1 - t0) * x.ease_slope;
      best_dy = top_slope;
      out.yarn_id = 1;
      out.thread = y.owner;
      have = true;
    }
  }

  if (!have) {
    // Gap: the fabric's underside; tangent, id and colour of the nearest yarn edge.
    out.gap = 0;
    out.height = floor_mm_ / unit;
    int nearest_end = 0, nearest_pick = 0;
    const double to_end = distance_to_nearest_yarn(ends_, x, nearest_end);
    const double to_pick = distance_to_nearest_yarn(picks_, y, nearest_pick);
    const bool warp_nearer = to_end <= to_pick;
    out.yarn_id = warp_nearer ? 0 : 1;
    out.thread = warp_nearer ? nearest_end : nearest_pick;
    const Thread& t =
        warp_nearer ? ends_[std::size_t(out.thread)] : picks_[std::size_t(out.thread)];
    out.color = t.color;
    const model::Vec3d axis = warp_nearer ? model::Vec3d{0, 1, 0} : model::Vec3d{1, 0, 0};
    out.tangent = twisted(axis, out.normal, t.cos_twist, t.sin_twist);
    return out;
  }

  // Tile units: u = x / W, v = y / H, h = z / W.
  out.height = best_z / unit;
  out.dh_du = best_dx * W / unit;
  out.dh_dv = best_dy * H / unit;
  out.normal = model::normalize(model::Vec3d{-out.dh_du, -out.dh_dv, 1.0});
  // The yarn axis on the surface: along v for the warp, along u for the weft, tilted by the
  // crimp. The cross-section does not change along the yarn, so the axis is orthogonal to the
  // normal and the twist rotation keeps the tangent in the tangent plane.
  const model::Vec3d axis = out.yarn_id == 0 ? model::normalize(model::Vec3d{0, 1, out.dh_dv})
                                             : model::normalize(model::Vec3d{1, 0, out.dh_du});
  const Thread& t = out.yarn_id == 0 ? end : pick;
  out.color = t.color;
  out.tangent = twisted(axis, out.normal, t.cos_twist, t.sin_twist);
  return out;
}

WeaveSample WeaveSurface::sample(double u, double v) const {
  auto wrap = [](double a) {
    double w = a - std::floor(a);
    return w >= 1.0 ? 0.0 : w;  // a tiny negative a rounds to 1.0
  };
  double x = wrap(u) * tile_.width_mm, y = wrap(v) * tile_.height_mm;
  if (x >= tile_.width_mm) x = 0;
  if (y >= tile_.height_mm) y = 0;
  return evaluate(locate_end(x), locate_pick(y));
}

FabricMaps generate_weave_maps(const WeaveSpec& spec, int resolution, const std::string& where) {
  if (resolution < 1 || resolution > kMaxMapResolution)
    throw_input_error(where + ": map resolution " + std::to_string(resolution) + " is outside 1.." +
                      std::to_string(kMaxMapResolution));
  const WeaveSurface surface(spec, where);
  const int n = resolution;
  // Each column (row) meets the same threads on every row (column): locate them once.
  std::vector<WeaveSurface::AxisPoint> columns(static_cast<std::size_t>(n));
  std::vector<WeaveSurface::AxisPoint> rows(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double c = (double(i) + 0.5) / double(n);
    columns[std::size_t(i)] = surface.locate_end(c * surface.tile().width_mm);
    rows[std::size_t(i)] = surface.locate_pick(c * surface.tile().height_mm);
  }
  FabricMaps maps;
  maps.allocate(n);
  auto to_float3 = [](const model::Vec3d& v) { return Vec3f{float(v.x), float(v.y), float(v.z)}; };
  tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& range) {
    for (int y = range.begin(); y < range.end(); ++y) {
      for (int x = 0; x < n; ++x) {
        const WeaveSample s = surface.evaluate(columns[std::size_t(x)], rows[std::size_t(y)]);
        const std::size_t i = maps.index(x, y);
        maps.height[i] = float(s.height);
        maps.tangent[i] = to_float3(s.tangent);
        maps.normal[i] = to_float3(s.normal);
        maps.gap[i] = s.gap;
        maps.yarn_id[i] = uint16_t(s.yarn_id);
        maps.albedo[i] = Vec3f{float(s.color[0]), float(s.color[1]), float(s.color[2])};
      }
    }
  });
  return maps;
}

}  // namespace clothbake::weave

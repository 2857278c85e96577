// Procedural feature maps of a woven fabric: one repeat of a weave rendered as an N x N tileable
// height field with fibre tangents, shading normals, gap indicator, yarn id and albedo.
//
// Geometry model (docs/weaves.md has the formulas and the references):
//  - the square tile is exactly one repeat of the weave matrix. Ends (warp threads) run along +y
//    and sit side by side along x; picks (weft threads) run along +x and sit along y. End e owns
//    the band [X_e, X_e + s_e) of the tile's physical width W = sum of end spacings, pick p the
//    band [Y_p, Y_p + s_p) of its physical height H = sum of pick spacings; u = x / W, v = y / H;
//  - heights are in tile-side units of the u side: height = z_mm / W. The shading normal is
//    normalize(-dh/du, -dh/dv, 1) of that height field, evaluated analytically at texel centres;
//    when H != W the tile is a non-uniformly scaled repeat (docs/weaves.md, "Non-square repeats");
//  - each yarn has an elliptical cross-section (half-width width * spacing / 2, half-height
//    height_mm / 2) whose centre follows a smooth crimp path: at each crossing it sits half the
//    crossing thread's thickness above (on top) or below it, with a cosine ease between crossings;
//  - the visible surface is the highest yarn at the texel; where no yarn covers the texel it is a
//    gap: I = 0 and the height is the lowest of the fabric (its underside);
//  - the fibre tangent is the yarn axis (tilted by the crimp slope) rotated about the surface
//  normal
//    by the twist angle: clockwise seen from above for twist_deg > 0 (Z twist), the same sense for
//    every thread of a system.
//
// Safe on untrusted input: validate_weave_spec() rejects every bad value with Error(Input) before
// any allocation proportional to it; generate_weave_maps() calls it.
#pragma once

#include <string>
#include <vector>

#include "bake/inputs/weave.hpp"
#include "fabric/fabric.hpp"
#include "model/vec.hpp"

namespace clothbake::weave {

// Largest map resolution generate_weave_maps accepts (16384^2 texels ~ 13 GB of maps).
inline constexpr int kMaxMapResolution = 16384;

struct YarnGeometry {       // per thread system (warp or weft), or per thread (overrides)
  double spacing_mm = 0.5;  // distance between neighbouring threads (the band a thread owns), > 0
  double width = 0.9;       // yarn width as a fraction of the spacing, (0, 1]; < 1 leaves gaps
  double height_mm = 0.15;  // yarn thickness, > 0 (the crossing yarn's crimp amplitude is half)
  double twist_deg = 20.0;  // fibre twist angle relative to the yarn axis, (-90, 90); > 0 = Z
};

struct WeaveSpec {
  WeaveMatrix matrix;
  YarnGeometry warp, weft;
  std::vector<Rgb> end_colors;   // per warp end (size ends) or empty (white); linear RGB in [0, 1]
  std::vector<Rgb> pick_colors;  // per pick (size picks) or empty (white); linear RGB in [0, 1]
  // Optional per-thread geometry (e.g. WIF [WARP SPACING] / [WARP THICKNESS]): size ends (picks)
  // or empty, in which case every end (pick) uses `warp` (`weft`).
  std::vector<YarnGeometry> end_geometry;
  std::vector<YarnGeometry> pick_geometry;
};

// Physical size of the tile (one repeat) and the unit of the height map.
struct TileSize {
  double width_mm = 0;        // W: along u (x), sum of the end spacings
  double height_mm = 0;       // H: along v (y), sum of the pick spacings
  double height_unit_mm = 0;  // one unit of the height map, = W
};

// Throws Error(Input) naming `where` and the offending field (e.g. "warp.width = 1.5 is outside
// (0, 1]", "end_colors has 3 entries, expected 4", "end 2 geometry: spacing_mm = 0"), or an
// unweavable matrix (check_weavable).
void validate_weave_spec(const WeaveSpec& spec, const std::string& where);

// W, H and the height unit of a valid spec.
TileSize weave_tile_size(const WeaveSpec& spec);

// The spec repeated `ends_times` across the ends and `picks_times` along the picks (each >= 1): the
// matrix tiled, the per-thread colours and geometry repeated in the same way (empty lists stay
// empty). A tile of several repeats, for a repeat far from square (docs/weaves.md, "Non-square
// repeats"). Throws Error(Input) naming `where` when the tiled matrix exceeds the largest repeat
// (make_matrix). Allocation: the new matrix and lists.
WeaveSpec repeat_weave_spec(const WeaveSpec& spec, int ends_times, int picks_times,
                            const std::string& where = "weave repeat");

// The surface at one point of the tile, in tile units (for tests, tools and inspection).
struct WeaveSample {
  double height = 0;              // tile-side units (height_unit_mm)
  double dh_du = 0, dh_dv = 0;    // analytic gradient of the height in tile units
  model::Vec3d tangent{0, 1, 0};  // unit fibre tangent (local frame, tile units)
  model::Vec3d normal{0, 0, 1};   // normalize(-dh_du, -dh_dv, 1)
  float gap = 1;                  // 1 = yarn, 0 = gap
  int yarn_id = 0;                // 0 = warp, 1 = weft
  int thread = 0;                 // index of the end (warp) or pick (weft) that owns the point
  Rgb color{1, 1, 1};             // colour of that thread
};

// Precomputed per-thread layout of a spec: build once, sample many times. Construction validates
// the spec (validate_weave_spec) and throws Error(Input) on a bad one.
class WeaveSurface {
 public:
  explicit WeaveSurface(const WeaveSpec& spec, const std::string& where = "weave");
  // (u, v) in tile units; any finite value, wrapped periodically into [0, 1)^2.
  WeaveSample sample(double u, double v) const;
  const TileSize& tile() const { return tile_; }
  // The height of gap texels: the underside of the fabric, below every yarn top (tile units).
  double floor_height() const { return floor_mm_ / tile_.height_unit_mm; }

  // One thread (end or pick), lengths in mm.
  struct Thread {
    double start = 0, spacing = 0, centre = 0;  // band [start, start + spacing) along its system
    double half_width = 0, half_height = 0;     // elliptical cross-section
    double cos_twist = 1, sin_twist = 0;
    Rgb color{1, 1, 1};
  };
  // Where a coordinate falls among the threads of one system (ends along x, picks along y).
  struct AxisPoint {
    int owner = 0;              // thread whose band holds the coordinate
    double offset = 0;          // coordinate - owner centre (mm)
    int before = 0, after = 0;  // the crossing threads either side (after = before + 1, wrapped)
    double ease = 0, ease_slope = 0;  // crimp blend (1 - cos(pi t)) / 2 and its derivative (1/mm)
  };
  // Locates a coordinate in [0, length) of the ends (x) or picks (y) system.
  AxisPoint locate_end(double x_mm) const { return locate(ends_, tile_.width_mm, x_mm); }
  AxisPoint locate_pick(double y_mm) const { return locate(picks_, tile_.height_mm, y_mm); }
  // The surface where column point `x` (over the ends) meets row point `y` (over the picks).
  WeaveSample evaluate(const AxisPoint& x, const AxisPoint& y) const;

 private:
  static AxisPoint locate(const std::vector<Thread>& threads, double length, double coord);

  WeaveMatrix matrix_;
  std::vector<Thread> ends_, picks_;
  TileSize tile_;
  double floor_mm_ = 0;
};

// N x N maps of one repeat of the weave on the unit tile: height (tile-side units), tangent,
// normal, gap I(x), yarn_id (0 = warp, 1 = weft), albedo (thread colour; gap texels take the colour
// of the nearest thread). Each texel is the analytic surface at its centre u = (x + 0.5) / N, so
// the maps are exactly periodic. Deterministic, independent of the thread count. Throws
// Error(Input) for a bad spec or resolution outside [1, kMaxMapResolution]; `where` prefixes those
// messages (e.g. "fabric.toml: [weave]").
FabricMaps generate_weave_maps(const WeaveSpec& spec, int resolution,
                               const std::string& where = "weave");

}  // namespace clothbake::weave

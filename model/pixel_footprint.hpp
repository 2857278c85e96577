// The pixel footprint rule (docs/rendering.md, "Pixel footprints"): a camera ray's differentials
// transferred to the surface's uv, and the axis-aligned rectangle that stands for the
// parallelogram one pixel covers there, in the units the caller scales
// the surface coordinates to (texels for clothbake's renderer, tile units for the Python module
// and its Mitsuba 3 plug-in).
//
// Here in model/ (header-only, C++17, standard library only) because the two renderers that shade
// clothbake assets, clothbake's own (render/camera.cpp) and Mitsuba 3 through the Python module
// (python/src/shading.cpp), must turn ray differentials into the same footprints, and model/ is
// the one layer both may include.
#pragma once

#include <cmath>

#include "model/vec.hpp"

namespace clothbake::model {

// The surface-coordinate derivatives of a pixel at a hit: dP/dx and dP/dy expressed in the
// (dP/du, dP/dv) basis. Units: surface (u, v) units per pixel.
struct UvDifferentials {
  double du_dx = 0, dv_dx = 0, du_dy = 0, dv_dy = 0;
};

// The uv derivatives of a camera ray's hit: the derivatives ddx, ddy of the ray's unit direction
// with respect to the pixel coordinates (the origin fixed) transferred to the hit's tangent plane,
// dP = t dD - ((t dD).n / (D.n)) D, and expressed in the (dpdu, dpdv) basis by least squares (the
// 2 x 2 Gram system). t: the hit distance along the unit direction; n: the geometric normal.
// Zero differentials where the ray grazes the surface (|D.n| <= 1e-12) or the basis is
// degenerate. Pure, no allocation; total on any input (non-finite inputs give non-finite or zero
// differentials, which pixel_footprint clamps).
inline UvDifferentials uv_differentials(double t, const Vec3d& direction, const Vec3d& ddx,
                                        const Vec3d& ddy, const Vec3d& normal, const Vec3d& dpdu,
                                        const Vec3d& dpdv) noexcept {
  UvDifferentials out;
  const double dn = dot(direction, normal);
  if (!(std::abs(dn) > 1e-12)) return out;
  const auto transfer = [&](const Vec3d& dd) {
    const Vec3d m = dd * t;
    return m - direction * (dot(m, normal) / dn);
  };
  const Vec3d px = transfer(ddx), py = transfer(ddy);
  const double a = dot(dpdu, dpdu), b = dot(dpdu, dpdv), c = dot(dpdv, dpdv);
  const double det = a * c - b * b;
  if (!(std::abs(det) > 1e-300)) return out;
  const auto solve = [&](const Vec3d& dp, double& du, double& dv) {
    const double ru = dot(dp, dpdu), rv = dot(dp, dpdv);
    du = (c * ru - b * rv) / det;
    dv = (a * rv - b * ru) / det;
  };
  solve(px, out.du_dx, out.dv_dx);
  solve(py, out.du_dy, out.dv_dy);
  return out;
}

// An axis-aligned rectangle [u0, u1] x [v0, v1] in the caller's scaled units.
struct FootprintRectangle {
  double u0 = 0, v0 = 0, u1 = 0, v1 = 0;
};

// The rectangle of a pixel centred at (u, v) (already in scaled units) whose parallelogram has
// edges (du_dx, dv_dx) and (du_dy, dv_dy) times `scale` (scaled units per surface unit): the
// parallelogram's axis-aligned bounding box, shrunk about its centre to the parallelogram's area,
// so that it keeps the box's aspect ratio and the pixel's true area. Each side is clamped to
// [0, max_side]; NaN or infinite differentials give max_side. Zero differentials give the point
// (u, v). Pure, no allocation; total on any input.
inline FootprintRectangle pixel_footprint(double u, double v, const UvDifferentials& d,
                                          double scale, double max_side) noexcept {
  double w = (std::abs(d.du_dx) + std::abs(d.du_dy)) * scale;
  double h = (std::abs(d.dv_dx) + std::abs(d.dv_dy)) * scale;
  const double area = std::abs(d.du_dx * d.dv_dy - d.du_dy * d.dv_dx) * scale * scale;
  if (w > 0 && h > 0 && area > 0 && area < w * h) {
    const double shrink = std::sqrt(area / (w * h));
    w *= shrink;
    h *= shrink;
  }
  if (!(w <= max_side)) w = max_side;  // NaN too
  if (!(h <= max_side)) h = max_side;
  return {u - 0.5 * w, v - 0.5 * h, u + 0.5 * w, v + 0.5 * h};
}

}  // namespace clothbake::model

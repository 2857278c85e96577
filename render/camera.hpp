// The pinhole camera and its ray differentials (docs/scene-format.md, "Camera"; the pixel
// footprint in texel space, docs/rendering.md "Pixel footprints").
//
// Pixel (i, j) covers [i, i + 1) x [j, j + 1) of the image plane, row 0 at the top; a camera ray
// through the continuous pixel position (x, y) and the derivatives of its unit direction with
// respect to x and y (the origin is fixed). Projected onto a surface, the two derivatives span the
// parallelogram that one pixel covers there; footprint_rectangle() turns it into the axis-aligned
// texel rectangle the summed-area tables need.
//
// C++20, no allocation; total on any camera the scene loader accepts.
#pragma once

#include "formats/reader/radiance_query.hpp"
#include "model/pixel_footprint.hpp"
#include "render/scene.hpp"
#include "render/shapes.hpp"

namespace clothbake::render {

struct CameraRay {
  Ray ray;
  Vec3 ddx, ddy;  // d(direction)/dx, d(direction)/dy per pixel
};

class PinholeCamera {
 public:
  explicit PinholeCamera(const Camera& camera);
  CameraRay generate(double x, double y) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  Vec3 origin_, forward_, right_, up_;  // right_ and up_ scaled to the image plane at distance 1
  int width_ = 0, height_ = 0;
};

// The surface-coordinate (u, v) derivatives of a pixel at a hit: dP/dx and dP/dy on the tangent
// plane (the ray differentials transferred to the hit), expressed in the (dpdu, dpdv) basis by
// least squares (model::uv_differentials, shared with the Mitsuba plug-in). Units: surface units
// per pixel.
using SurfaceDifferentials = model::UvDifferentials;
SurfaceDifferentials surface_differentials(const CameraRay& ray, const SurfaceHit& hit);

// The texel rectangle of a pixel: the axis-aligned box of the pixel's parallelogram (centred at
// the hit, edges (du_dx, dv_dx) and (du_dy, dv_dy) times texels_per_unit), shrunk about its centre
// to the parallelogram's area, so that the rectangle has the box's aspect ratio and the pixel's
// true area (docs/rendering.md): model::pixel_footprint, the rule the Mitsuba plug-in shares, with
// sides clamped to [0, 2^30] texels.
reader::Footprint footprint_rectangle(double u_texels, double v_texels,
                                      const SurfaceDifferentials& d, double texels_per_unit);

}  // namespace clothbake::render

// What the shading of a scene can ask of each fabric (docs/scene-format.md, "Usage analysis"):
// the pixel footprints in texels, the view, light and half-vector directions, whether light
// reaches the side of the cloth opposite to the viewer, and how grazing the views are. The
// primary rays, footprints and shadow rays are the renderer's own (PinholeCamera,
// footprint_rectangle, ShadingFrame, shadow_ray_origin): the analysis sees what the renderer
// would query, at the pixel centres the renderer shades.
//
// Directions are in the object's shading frame (z = the surface normal, x = the fabric's u
// axis). Light directions come from every light: a point light's direction from the hit, a
// directional light's reverse travel direction, and for an environment light a fixed set of
// kEnvironmentDirections directions (a spherical Fibonacci set) where the map is not black; each
// only when no object blocks it (the shadow rays of the renderer).
//
// C++20, deterministic for any thread count (per-row partial results merged in row order).
// Total on any scene the scene loader accepts; nothing is read or written.
#pragma once

#include <cstdint>
#include <vector>

#include "render/scene.hpp"

namespace clothbake::render {

inline constexpr int kEnvironmentDirections = 256;

// What a fabric's bake settings are, per object (the analysis needs no asset).
struct FabricShape {
  int resolution = 0;     // N texels per tile side; 0: the object is not analysed (diffuse)
  int radiance_dirs = 0;  // half-vector bins per side of the Integral-Radiance tables
  int parallax_dirs = 0;  // view directions per side of the parallax table (0: not analysed)
  double parallax_min_cos = 0.6;  // its cap
};

// Grazing: a view or light direction within 20 degrees of the surface (|cos| < cos 70 degrees).
inline constexpr double kGrazingCos = 0.3420201433256687;

struct ObjectUsage {
  int object = -1;
  uint64_t pixels = 0;  // pixels whose primary ray hits the object
  // Footprint size as the side of the square of the same area, sqrt(|P|), in texels, over those
  // pixels: smallest, 5th percentile, median, largest (0 when no pixel sees the object).
  double footprint_min = 0, footprint_p05 = 0, footprint_median = 0, footprint_max = 0;
  // Views: smallest |cos| of the view direction to the normal, share of grazing views.
  double min_view_cos = 1, grazing_view_fraction = 0;
  bool views_front = false, views_back = false;  // wo.z > 0 / < 0 somewhere
  // Light: pairs (pixel, light direction) that are not shadowed, split by the side of the light
  // relative to the viewer; the smallest |cos| of a lit direction.
  uint64_t lit_same_side = 0, lit_opposite_side = 0;
  double min_light_cos = 1;
  // Half vectors h = wi + wo of every lit pair (folded to h.z >= 0 as the tables do):
  // the radiance_dirs^2 bins whose bilinear support some h touches (1 = used), and the largest
  // angle of a folded h to the normal, radians.
  std::vector<uint8_t> half_vector_bins;
  double max_half_vector_angle = 0;
  uint64_t half_vector_bins_used() const;
  // View directions as the parallax table looks them up (mirrored to o_z >= 0, moved onto the
  // cap's rim below parallax_min_cos): the parallax_dirs^2 bins of DirectionGrid{parallax_dirs,
  // parallax_min_cos} whose bilinear support (weight > 0) some pixel's view touches (1 = used).
  std::vector<uint8_t> view_bins;
  uint64_t view_bins_used() const;
  bool back_lit() const { return lit_opposite_side > 0; }
};

struct SceneUsage {
  std::vector<ObjectUsage> objects;  // one per scene object (pixels = 0 for the ones not analysed)
  double max_error = 0.008;          // the scene's [render] max_error
};

// `shapes` has one entry per scene object. Throws nothing: objects with resolution 0 are skipped.
SceneUsage analyse_usage(const Scene& scene, const std::vector<FabricShape>& shapes);

}  // namespace clothbake::render

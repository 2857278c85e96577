// Ray intersection and surface parameterisation of the scene's analytic shapes (docs/scene-
// format.md, "Objects"): finite planes, open cylinders and spheres, each with arc-length surface
// coordinates (u, v) in world units and their tangents.
//
// C++20, header-declared, no allocation; total on any finite input (degenerate shapes never hit).
#pragma once

#include <limits>

#include "render/scene.hpp"

namespace clothbake::render {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // unit
};

struct SurfaceHit {
  double t = std::numeric_limits<double>::infinity();  // ray parameter (distance)
  int object = -1;
  Vec3 point;
  Vec3 normal;      // unit geometric normal (outward for closed shapes, the plane's normal)
  Vec3 dpdu, dpdv;  // dP/du, dP/dv (u, v in world units of arc length)
  double u = 0, v = 0;
  bool hit() const { return object >= 0; }
};

// The nearest hit of `ray` with `object` in (t_min, t_max), or no hit (t stays infinite).
SurfaceHit intersect(const Ray& ray, const Object& object, double t_min, double t_max);

// The nearest hit over every object of the scene.
SurfaceHit intersect_scene(const Ray& ray, const std::vector<Object>& objects, double t_min,
                           double t_max);

// Whether anything blocks the segment (t_min, t_max) of the ray.
bool occluded(const Ray& ray, const std::vector<Object>& objects, double t_min, double t_max);

// Whether a point lies strictly inside a closed shape (sphere; the volume a cylinder encloses).
bool inside(const Object& object, const Vec3& point);

// The orthonormal frame of an object's axis (cylinder, sphere): e1, e2 perpendicular to it.
void axis_frame(const Vec3& axis, Vec3& e1, Vec3& e2);

}  // namespace clothbake::render

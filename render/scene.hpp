// A scene to render: a pinhole camera, lights and objects (docs/scene-format.md). Plain data: the
// TOML description is parsed by bake/inputs/scene_load.hpp, which resolves every path; nothing
// here reads files.
//
// Units and frames: world space is right-handed with arbitrary units; surfaces carry arc-length
// coordinates (u, v) in world units, so `tiles_per_unit` tiles of the fabric cover one unit of
// surface. Light intensities are linear RGB: a point light's radiant intensity (W/sr), a
// directional light's irradiance on a surface facing it (W/m^2), an environment map's radiance.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/rgb.hpp"
#include "model/vec.hpp"

namespace clothbake::render {

using Vec3 = model::Vec3d;
using Rgb = model::Rgb<double>;

struct Camera {
  Vec3 position{0, 0, 5};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 1, 0};
  double fov_deg = 40;  // vertical field of view, (0, 180)
  int width = 256, height = 256;
};

// An equirectangular (lat-long) radiance map with +y up: pixel (x, y) covers the azimuth
// phi in [2 pi x / W, 2 pi (x + 1) / W) and the polar angle theta in [pi y / H, pi (y + 1) / H),
// direction (sin theta cos phi, cos theta, sin theta sin phi) (environment.hpp). Row 0 is the
// zenith.
struct EnvironmentMap {
  int width = 0, height = 0;
  std::vector<float> rgb;  // width * height * 3, linear RGB radiance
  double scale = 1;
};

enum class LightType : uint8_t { Point, Directional, Environment };

struct Light {
  std::string name;  // "light[0]" for messages
  LightType type = LightType::Point;
  Vec3 position;               // point
  Rgb intensity{1};            // point: radiant intensity
  Vec3 direction{0, -1, 0};    // directional: the direction the light travels (unit)
  Rgb irradiance{1};           // directional
  EnvironmentMap environment;  // environment
};

enum class ShapeType : uint8_t { Plane, Cylinder, Sphere };

struct Object {
  std::string name;  // "object[0]" for messages
  ShapeType shape = ShapeType::Plane;
  Vec3 center;
  // plane: unit normal and tangent (orthogonalised: u runs along the tangent), size along u, v
  Vec3 normal{0, 0, 1}, tangent{1, 0, 0};
  double size[2] = {1, 1};
  // cylinder (open, no caps; u around the axis, v along it) and sphere (u around the axis, v from
  // the pole along the meridian)
  Vec3 axis{0, 1, 0};
  double radius = 1, height = 1;
  std::string asset;  // the fabric's .cbk; empty: a Lambertian surface of colour `diffuse`
  double tiles_per_unit = 1;
  Rgb diffuse{0.5};
};

struct Scene {
  std::string path;  // the scene file, for messages
  Camera camera;
  std::vector<Light> lights;
  std::vector<Object> objects;
  double max_error = 0.008;  // [render] max_error: the scene's error budget (relative)
};

}  // namespace clothbake::render

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
  // Fabric tiles per world unit: given, or the scene's unit length over the tile's physical side
  // (`units` with `tile_mm` or the fabric's own tile size, docs/scene-format.md).
  double tiles_per_unit = 1;
  Rgb diffuse{0.5};
};

// How the 8-bit PNG preview maps linear radiance to display values (the EXR stays linear):
// Clamp: min(x, 1); Reinhard: the luminance L to L / (1 + L), the colour scaled with it, then
// clamped; Filmic: Narkowicz's fit of the ACES curve per channel, x (2.51 x + 0.03) / (x (2.43 x +
// 0.59) + 0.14) clamped to [0, 1]. Then the sRGB transfer function (image_output.hpp).
enum class ToneMap : uint8_t { Clamp, Reinhard, Filmic };

// Largest |exposure| accepted, in stops (2^32: any radiance a render can have fits in the range).
inline constexpr double kMaxExposureStops = 32;

struct Preview {
  double exposure = 0;  // stops: the linear values are scaled by 2^exposure before the tone map
  ToneMap tone_map = ToneMap::Clamp;
};

struct Scene {
  std::string path;  // the scene file, for messages
  Camera camera;
  std::vector<Light> lights;
  std::vector<Object> objects;
  double max_error = 0.008;  // [render] max_error: the scene's error budget (relative)
  Preview preview;           // [render] exposure, tone_map: the PNG preview only
  // [render] background: the radiance camera rays see where they leave the scene, directly and
  // through the cloth's gaps (the delta lobe); it lights nothing. Only without an environment
  // light (whose map is then the background).
  Rgb background{0};
};

}  // namespace clothbake::render

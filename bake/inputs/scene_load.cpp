// Scene descriptions (scene_load.hpp).
#include "bake/inputs/scene_load.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <optional>

#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/fabric_toml.hpp"
#include "bake/inputs/input_kind.hpp"
#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "render/shapes.hpp"

namespace clothbake::inputs {
namespace {

namespace fs = std::filesystem;
using render::Vec3;

const Range kAnyFinite{};
const Range kPositive{0, 1e12, true, false};
const Range kNonNegative{0, 1e12, false, false};

Vec3 vec3(const TomlSection& s, std::string_view key, const Vec3& fallback) {
  const auto v = s.numbers(key, 3, kAnyFinite);
  return v ? Vec3((*v)[0], (*v)[1], (*v)[2]) : fallback;
}

Vec3 unit(const TomlSection& s, std::string_view key, const Vec3& fallback) {
  const Vec3 v = vec3(s, key, fallback);
  const double len = length(v);
  if (!(len > 1e-12) || !std::isfinite(len)) s.fail(key, "must be a non-zero vector");
  return v / len;
}

render::Rgb colour(const TomlSection& s, std::string_view key, const render::Rgb& fallback,
                   const Range& range) {
  const auto c = s.rgb(key, range);
  return c ? render::Rgb((*c)[0], (*c)[1], (*c)[2]) : fallback;
}

std::string resolve(const TomlSection& s, std::string_view key, const fs::path& base) {
  const std::string value = *s.string(key);
  if (value.empty()) s.fail(key, "must not be empty");
  const fs::path p = fs::path(value).is_absolute() ? fs::path(value) : base / value;
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    s.fail(key, fmt::format("= \"{}\": {} is not a readable file", value, p.string()));
  return p.string();
}

render::Camera load_camera(const TomlSection& c) {
  c.check_keys({"position", "look_at", "up", "fov_deg", "resolution"});
  render::Camera cam;
  cam.position = vec3(c, "position", cam.position);
  cam.look_at = vec3(c, "look_at", cam.look_at);
  cam.up = unit(c, "up", cam.up);
  cam.fov_deg = c.real("fov_deg", Range{0, 180, true, true}).value_or(cam.fov_deg);
  if (const auto r = c.numbers("resolution", 2, Range{1, 16384})) {
    if ((*r)[0] != std::floor((*r)[0]) || (*r)[1] != std::floor((*r)[1]))
      c.fail("resolution", "must be two integers [width, height]");
    cam.width = int((*r)[0]);
    cam.height = int((*r)[1]);
  }
  const Vec3 forward = cam.look_at - cam.position;
  if (!(length(forward) > 1e-12)) c.fail("look_at", "must differ from the camera position");
  if (!(length(cross(normalize(forward), cam.up)) > 1e-6))
    c.fail("up", "must not be parallel to the viewing direction");
  return cam;
}

render::Light load_light(const TomlSection& l, std::size_t index, const fs::path& base) {
  render::Light light;
  light.name = fmt::format("light[{}]", index);
  if (!l.has("type")) l.fail("type", "is required (point, directional or environment)");
  const std::string type = *l.choice("type", {"point", "directional", "environment"});
  if (type == "point") {
    l.check_keys({"type", "position", "intensity"});
    light.type = render::LightType::Point;
    if (!l.has("position")) l.fail("position", "is required for a point light");
    light.position = vec3(l, "position", {});
    light.intensity = colour(l, "intensity", light.intensity, kNonNegative);
  } else if (type == "directional") {
    l.check_keys({"type", "direction", "irradiance"});
    light.type = render::LightType::Directional;
    if (!l.has("direction")) l.fail("direction", "is required for a directional light");
    light.direction = unit(l, "direction", {});
    light.irradiance = colour(l, "irradiance", light.irradiance, kNonNegative);
  } else {
    l.check_keys({"type", "map", "scale"});
    light.type = render::LightType::Environment;
    if (!l.has("map")) l.fail("map", "is required for an environment light (a lat-long EXR)");
    const std::string path = resolve(l, "map", base);
    // The first three channels (RGB; others ignored), sides and pixel count checked from the
    // header before any pixel is allocated.
    ImageReadLimits limits;
    limits.max_side = kMaxEnvironmentSide;
    limits.max_pixels = kMaxEnvironmentPixels;
    limits.first_channels = 3;
    Image image;
    try {
      image = read_image(path, limits);
    } catch (const Error& e) {
      l.fail("map", e.what());
    }
    render::EnvironmentMap& env = light.environment;
    env.width = image.width;
    env.height = image.height;
    env.scale = l.real("scale", kNonNegative).value_or(1.0);
    env.rgb.resize(std::size_t(env.width) * env.height * 3);
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        for (int c = 0; c < 3; ++c) {
          const float v = image.at(x, y, c);
          if (!std::isfinite(v) || v < 0)
            l.fail("map", fmt::format("{}: pixel ({}, {}) channel {} is {}, not a finite radiance "
                                      ">= 0",
                                      path, x, y, c, v));
          env.rgb[(std::size_t(y) * env.width + x) * 3 + c] = v;
        }
  }
  return light;
}

constexpr int kTileSideResolution = 64;

// The physical side of the tile of the fabric an object names, in mm (0: the fabric gives none):
// from the asset's FabricInfo record, or from loading the fabric description.
double fabric_tile_mm(const TomlSection& o, const render::Object& obj, const std::string& fabric) {
  if (!fabric.empty()) {
    // A weave's tile side does not depend on its resolution: generated at 64 texels it costs
    // milliseconds whatever [bake] resolution says (the bake's memory check comes later, before
    // the real load). Image fabrics are loaded as they are (their maps' sizes are bounded).
    LoadOptions options;
    const auto peek = peek_fabric_settings(fabric);
    if (peek && !peek->image_maps) options.resolution = kTileSideResolution;
    return load_fabric_description(fabric, options).fabric.tile_size_mm;
  }
  reader::Asset asset;
  const reader::FabricInfoRecord* info = nullptr;
  // Every checksum, as every command checks an asset before it answers from it.
  if (!asset.open_file(obj.asset.c_str()).ok() || !reader::verify_checksums(asset).ok() ||
      !reader::read_fabric_info(asset, &info).ok())
    o.fail("asset", fmt::format("= {}: cannot read the asset's tile size (`clothbake validate` "
                                "says why); give tile_mm or tiles_per_unit",
                                obj.asset));
  return std::isfinite(info->tile_size_mm) && info->tile_size_mm > 0 ? info->tile_size_mm : 0.0;
}

// How many tiles of the object's fabric cover one world unit: `tiles_per_unit`, or the scene's
// unit length (`units`, unit_mm > 0) over `tile_mm` or over the fabric's own tile side.
double tiles_per_unit(const TomlSection& o, const render::Object& obj, const std::string& fabric,
                      double unit_mm) {
  if (o.has("tiles_per_unit") && o.has("tile_mm"))
    o.fail("tile_mm",
           "and tiles_per_unit are exclusive: give the tile's physical side (with the "
           "scene's units) or the tiles per world unit");
  if (o.has("tiles_per_unit")) return *o.real("tiles_per_unit", kPositive);
  // The unit's length over a tile side, within tiles_per_unit's own range (naming `key`).
  auto per_unit = [&](double tile_mm, const char* key) {
    const double tiles = unit_mm / tile_mm;
    if (!(tiles <= kPositive.hi))
      o.fail(key, fmt::format("gives {} tiles per world unit, more than {}", tiles, kPositive.hi));
    return tiles;
  };
  if (o.has("tile_mm")) {
    const double tile_mm = *o.real("tile_mm", kPositive);
    if (!(unit_mm > 0))
      o.fail("tile_mm",
             "needs the scene's length unit: a top-level units = \"m\" (or \"cm\", "
             "\"mm\", \"in\") before the first table");
    return per_unit(tile_mm, "tile_mm");
  }
  if (!(unit_mm > 0) || (obj.asset.empty() && fabric.empty())) return obj.tiles_per_unit;
  const char* key = fabric.empty() ? "asset" : "fabric";
  const double tile_mm = fabric_tile_mm(o, obj, fabric);
  if (!(tile_mm > 0))
    o.fail(key,
           fmt::format("= {}: the fabric gives no physical tile size ([tile] units = \"tile\"), "
                       "so the scene's units cannot place it; give tile_mm or tiles_per_unit",
                       fabric.empty() ? obj.asset : fabric));
  return per_unit(tile_mm, key);
}

render::Object load_object(const TomlSection& o, std::size_t index, const fs::path& base,
                           double unit_mm, std::string* fabric) {
  render::Object obj;
  obj.name = fmt::format("object[{}]", index);
  if (!o.has("shape")) o.fail("shape", "is required (plane, cylinder or sphere)");
  const std::string shape = *o.choice("shape", {"plane", "cylinder", "sphere"});
  std::vector<std::string> keys = {"shape",  "name",           "center",  "asset",
                                   "fabric", "tiles_per_unit", "tile_mm", "color"};
  if (shape == "plane") {
    obj.shape = render::ShapeType::Plane;
    keys.insert(keys.end(), {"normal", "tangent", "size"});
  } else if (shape == "cylinder") {
    obj.shape = render::ShapeType::Cylinder;
    keys.insert(keys.end(), {"axis", "radius", "height"});
  } else {
    obj.shape = render::ShapeType::Sphere;
    keys.insert(keys.end(), {"axis", "radius"});
  }
  o.check_keys(keys);
  if (const auto name = o.string("name")) obj.name = fmt::format("object[{}] ({})", index, *name);
  obj.center = vec3(o, "center", obj.center);
  if (obj.shape == render::ShapeType::Plane) {
    obj.normal = unit(o, "normal", obj.normal);
    obj.tangent = unit(o, "tangent", obj.tangent);
    if (!(length(cross(obj.normal, obj.tangent)) > 1e-6))
      o.fail("tangent", "must not be parallel to the normal");
    if (const auto size = o.numbers("size", 2, kPositive)) {
      obj.size[0] = (*size)[0];
      obj.size[1] = (*size)[1];
    }
  } else {
    obj.axis = unit(o, "axis", obj.axis);
    obj.radius = o.real("radius", kPositive).value_or(obj.radius);
    if (obj.shape == render::ShapeType::Cylinder)
      obj.height = o.real("height", kPositive).value_or(obj.height);
  }
  if (o.has("asset") && o.has("fabric"))
    o.fail("fabric", "and asset are exclusive: give the baked asset or the fabric to bake");
  if (o.has("asset")) obj.asset = resolve(o, "asset", base);
  if (o.has("fabric")) *fabric = resolve(o, "fabric", base);
  obj.tiles_per_unit = tiles_per_unit(o, obj, *fabric, unit_mm);
  obj.diffuse = colour(o, "color", obj.diffuse, Range{0, 1});
  return obj;
}

}  // namespace

LoadedScene load_scene(const std::string& path) {
  const std::string text = read_file_bytes(path);
  require_input_kind(sniff_input_kind(text), path, InputKind::Scene,
                     "this command needs a scene (docs/scene-format.md); bake, inspect and "
                     "pattern take fabrics");
  const toml::table root_table = parse_toml_text(text, path);
  const TomlSection root(root_table, path, "");
  root.check_keys({"units", "camera", "light", "object", "render"});
  double unit_mm = 0;  // the length of one world unit; 0: not given (arbitrary units)
  if (const auto units = root.choice("units", kPhysicalLengthUnits))
    unit_mm = length_unit_in_mm(*units);
  const fs::path base = fs::path(path).parent_path();
  LoadedScene out;
  render::Scene& scene = out.scene;
  scene.path = path;
  const auto camera = root.table("camera");
  if (!camera)
    root.fail("camera", "is required: [camera] position, look_at, up, fov_deg, resolution");
  scene.camera = load_camera(*camera);
  std::optional<TomlSection> render_table = root.table("render");
  if (const auto& r = render_table) {
    r->check_keys({"max_error", "exposure", "tone_map", "background"});
    scene.max_error = r->real("max_error", Range{0, 1, true, false}).value_or(scene.max_error);
    scene.preview.exposure =
        r->real("exposure", Range{-render::kMaxExposureStops, render::kMaxExposureStops})
            .value_or(scene.preview.exposure);
    if (const auto tone = r->choice("tone_map", {"clamp", "reinhard", "filmic"}))
      scene.preview.tone_map = *tone == "clamp"      ? render::ToneMap::Clamp
                               : *tone == "reinhard" ? render::ToneMap::Reinhard
                                                     : render::ToneMap::Filmic;
    scene.background = colour(*r, "background", scene.background, kNonNegative);
  }
  if (const auto lights = root.table_array("light"))
    for (std::size_t k = 0; k < lights->size(); ++k)
      scene.lights.push_back(load_light((*lights)[k], k, base));
  if (const auto objects = root.table_array("object"))
    for (std::size_t k = 0; k < objects->size(); ++k) {
      std::string fabric;
      scene.objects.push_back(load_object((*objects)[k], k, base, unit_mm, &fabric));
      out.fabrics.push_back(fabric);
    }
  if (scene.objects.empty()) root.fail("object", "the scene has no [[object]]");
  if (scene.lights.empty()) root.fail("light", "the scene has no [[light]]");
  if (render_table && render_table->has("background"))
    for (const render::Light& l : scene.lights)
      if (l.type == render::LightType::Environment)
        render_table->fail("background", fmt::format("and {}, an environment light, are exclusive: "
                                                     "the environment map is the background",
                                                     l.name));
  const auto lights = root.table_array("light");
  for (std::size_t k = 0; k < scene.lights.size(); ++k) {
    const render::Light& l = scene.lights[k];
    if (l.type != render::LightType::Point) continue;
    for (const render::Object& o : scene.objects)
      if (render::inside(o, l.position))
        (*lights)[k].fail("position", fmt::format("is inside {}: the light could not reach the "
                                                  "scene",
                                                  o.name));
  }
  return out;
}

}  // namespace clothbake::inputs

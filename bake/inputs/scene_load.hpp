// Loads a scene description (TOML, docs/scene-format.md) into render::Scene: strict keys with a
// "did you mean" suggestion, every value checked (finite, in range), every path resolved relative
// to the scene file, environment maps read with OpenImageIO, and the geometric sanity checks the
// renderer relies on (a point light inside a closed object, a degenerate camera or shape).
//
// Errors: clothbake::Error(Input) naming the file, line, column and dotted key ("light[1].position
// [2] = nan is out of range"); nothing else is read or written.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/scene.hpp"

namespace clothbake::inputs {

// Largest environment map accepted (checked from the file's header, before any allocation): sides
// of at most 16384 pixels and 2^25 pixels in all (8192 x 4096). docs/hardening.md gives the memory
// this bounds.
inline constexpr int kMaxEnvironmentSide = 16384;
inline constexpr uint64_t kMaxEnvironmentPixels = uint64_t(1) << 25;

// A scene with the fabric of every object that names one (`fabric = "f.toml"`, resolved):
// fabrics[k] is the fabric path of objects[k] (empty for `asset =` and diffuse objects); the
// caller bakes them and fills scene.objects[k].asset.
struct LoadedScene {
  render::Scene scene;
  std::vector<std::string> fabrics;
};

LoadedScene load_scene(const std::string& path);

}  // namespace clothbake::inputs

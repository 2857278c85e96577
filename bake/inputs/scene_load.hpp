// Loads a scene description (TOML, docs/scene-format.md) into render::Scene: strict keys with a
// "did you mean" suggestion, every value checked (finite, in range), every path resolved relative
// to the scene file, environment maps read with OpenImageIO, and the geometric sanity checks the
// renderer relies on (a point light inside a closed object, a degenerate camera or shape).
//
// Errors: clothbake::Error(Input) naming the file, line, column and dotted key ("light[1].position
// [2] = nan is out of range"); nothing else is read or written.
#pragma once

#include <string>
#include <vector>

#include "render/scene.hpp"

namespace clothbake::inputs {

// A scene with the fabric of every object that names one (`fabric = "f.toml"`, resolved):
// fabrics[k] is the fabric path of objects[k] (empty for `asset =` and diffuse objects); the
// caller bakes them and fills scene.objects[k].asset.
struct LoadedScene {
  render::Scene scene;
  std::vector<std::string> fabrics;
};

LoadedScene load_scene(const std::string& path);

}  // namespace clothbake::inputs

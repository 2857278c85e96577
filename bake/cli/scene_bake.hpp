// Assets for the objects of a scene that name a fabric (`fabric = "f.toml"`): each is baked once
// into a cache folder, keyed by the content of its inputs, and the scene object is pointed at it
// (docs/scene-format.md, "Fabrics baked on the fly").
#pragma once

#include <string>

#include "bake/inputs/scene_load.hpp"

namespace clothbake::cli {

// The cache folder: `option` when given, else $CLOTHBAKE_CACHE, else $HOME/.cache/clothbake.
std::string scene_cache_dir(const std::string& option);

// For every objects[k] with fabrics[k] set: loads the fabric, computes its key (XXH64 of the tool
// version, every input file's content hash and the resolved bake settings), bakes it to
// CACHE/<name>-<key>.cbk unless that file exists, and sets objects[k].asset. Throws
// clothbake::Error (Input for a bad fabric or an unwritable cache).
void bake_scene_fabrics(inputs::LoadedScene& scene, const std::string& cache_option, bool quiet);

}  // namespace clothbake::cli

// A bake plan from a scene (docs/scene-format.md, "Bake plans"): the usage analysis of the scene
// (render/usage_analysis.hpp) turned, per fabric, into what an asset needs: per-texel parallax,
// the transmission and gap tables, the half-vector bins, the sheen, the directional resolution
// (2-sigma rule) and the compression target from the scene's error budget, each with the reason
// in words. `clothbake plan` prints it; baking a plan is not implemented yet (the format has no
// bin map), so every decision is a proposal.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bake/inputs/scene_load.hpp"
#include "fabric/fabric.hpp"
#include "render/usage_analysis.hpp"

namespace clothbake::cli {

struct PlanDecision {
  std::string item;      // "per-texel parallax", "transmission and gap tables", ...
  std::string decision;  // "kept", "left out", "reduced"
  std::string reason;    // in words, with the figures
};

struct FabricPlan {
  int object = -1;
  std::string object_name, fabric_path;
  render::ObjectUsage usage;
  int resolution = 0, radiance_dirs = 0, half_vector_bins_total = 0;
  double max_parallax_offset = 0;  // texels, over the scene's views
  std::vector<PlanDecision> decisions;
  std::vector<std::string> warnings;
};

struct ScenePlan {
  std::string scene;
  double max_error = 0;
  std::vector<FabricPlan> fabrics;  // one per object with `fabric =`
};

// The rules on one fabric's usage (pure; documented in docs/scene-format.md).
FabricPlan plan_fabric(const Fabric& fabric, const render::ObjectUsage& usage, double max_error);

// Loads every `fabric =` object's fabric (maps included), analyses the scene and plans each.
// Objects with `asset =` or a diffuse colour are not planned (they are baked already or need
// nothing). Throws clothbake::Error(Input) for a bad scene or fabric.
ScenePlan plan_scene(const inputs::LoadedScene& scene);

nlohmann::json plan_json(const ScenePlan& plan);

}  // namespace clothbake::cli

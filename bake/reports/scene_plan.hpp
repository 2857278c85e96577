// A bake plan from a scene (docs/scene-format.md, "Bake plans"): the usage analysis of the scene
// (render/usage_analysis.hpp) turned, per fabric, into what an asset needs: per-texel parallax,
// the transmission and gap tables, the half-vector bins, the sheen, the directional resolution
// (2-sigma rule) and the compression target from the scene's error budget, each with the reason
// in words. `clothbake plan` prints it; `clothbake bake --scene` bakes it (bin maps:
// docs/scene-plans.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bake/inputs/scene_load.hpp"
#include "fabric/fabric.hpp"
#include "render/usage_analysis.hpp"

namespace clothbake::reports {

struct PlanDecision {
  std::string item;      // "per-texel parallax", "transmission and gap tables", ...
  std::string decision;  // "kept", "left out", "reduced"
  std::string reason;    // in words, with the figures
};

// Estimated asset size and bake time of the full bake and of the plan (scene_plan.cpp, "Estimates":
// sizes from the format's section shapes, the compressed tables from the measured mean rank; times
// from per-stage rates measured on the 256^2 twill, docs/scene-plans.md).
struct PlanEstimate {
  uint64_t full_bytes = 0, planned_bytes = 0;
  double full_seconds = 0, planned_seconds = 0;
};

struct FabricPlan {
  int object = -1;
  std::string object_name, fabric_path;
  render::ObjectUsage usage;
  int resolution = 0, radiance_dirs = 0, half_vector_bins_total = 0, parallax_dirs = 0;
  // Light directions per side of the visibility sampling: the fabric's, and the plan's (fewer
  // where every footprint is wide; docs/scene-plans.md, "Visibility directions").
  int fabric_visibility_dirs = 0, visibility_dirs = 0;
  double max_parallax_offset = 0;  // texels, over the scene's views
  // The planned parallax codes' RMS offset error (texels, planned_parallax_error); the fabric's
  // [bake] parallax_max_error when the footprints do not allow a looser one.
  double parallax_max_error = 0;
  // The planned tables' target (relative RMS per texel, planned_compression_target); 0 when the
  // fabric asks for a fixed C-PCA shape, which the plan keeps.
  double compression_target = 0;
  std::vector<PlanDecision> decisions;
  std::vector<std::string> warnings;
  PlanEstimate estimate;
};

struct ScenePlan {
  std::string scene;
  double max_error = 0;
  std::vector<FabricPlan> fabrics;  // one per object with `fabric =`
};

// The compressed tables' target of a plan (relative RMS error per texel, docs/scene-plans.md,
// "Compression target"): the default bake's target `default_target` when the budget (the scene's
// [render] max_error, a relMSE) allows it, i.e. when (e + default_target)^2 <= budget / 2 holds
// for e = default_target; below that budget the loosest e that satisfies it, but no tighter than
// default_target / 4. Looser than the default is never chosen: the unbiased estimate's expected
// picture does not depend on the tables, its noise does. Pure.
double planned_compression_target(double default_target, double budget);

// The planned parallax codes' RMS offset error in texels (docs/scene-plans.md, "Parallax
// precision"): quantising a depth moves a point's destination by at most the offset error e, so a
// footprint of side s gains or loses at most the boundary strip 4 e s of its s^2 area, a relative
// error 4 e / s, a relMSE (4 e / s)^2; the loosest e with (4 e / s_min)^2 <= budget / 16 (a
// sixteenth of the budget: the bound is reached on oblique mid-field views, and the budget is
// mostly the picture's, planned_compression_target takes up to half), but never tighter than the
// fabric's `default_error` and never looser than one texel. `budget` is the scene's [render]
// max_error (a relMSE), `footprint_min` the smallest footprint side in texels. Pure.
double planned_parallax_error(double default_error, double budget, double footprint_min);

// The rules on one fabric's usage (pure; documented in docs/scene-format.md).
FabricPlan plan_fabric(const Fabric& fabric, const render::ObjectUsage& usage, double max_error);

// Loads every `fabric =` object's fabric (maps included), analyses the scene and plans each.
// Objects with `asset =` or a diffuse colour are not planned (they are baked already or need
// nothing). Throws clothbake::Error(Input) for a bad scene or fabric.
ScenePlan plan_scene(const inputs::LoadedScene& scene);

nlohmann::json plan_json(const ScenePlan& plan);

}  // namespace clothbake::reports

#include "bake/pipeline/bake.hpp"

namespace clothbake::reports {

// What `bake --scene` needs to bake one fabric's plan: the stages' seed, the sections that record
// the plan (bin maps, ScenePlanRecord) and the metadata (the plan's decisions, the scene's path
// and content hash, what was left out).
struct ScenePlanSeeds {
  std::string scene_hash;             // XXH64 of the scene file, 16 hex digits
  std::vector<std::string> left_out;  // in words, for messages and `info`
  uint32_t half_vector_bins_kept = 0, half_vector_bins_total = 0;
  uint32_t view_bins_kept = 0, view_bins_total = 0;
  int visibility_dirs = 0, visibility_dirs_total = 0;  // per side: planned, the fabric's
  bool transmission = true;
  nlohmann::json metadata;
};

// Plans `fabric_path` for the scene at `scene_path` (every object that names this fabric file,
// their usages merged) and puts the seeds into `request`. Throws clothbake::Error(Input), exit 2,
// before anything is baked: a scene that does not use the fabric (naming the fabrics it does use),
// a plan that leaves out everything (no pixel sees the fabric, or no light reaches it).
ScenePlanSeeds seed_scene_plan(const std::string& scene_path, const std::string& fabric_path,
                               pipeline::BakeRequest* request);
// The same for a scene already loaded (and possibly changed, e.g. another image size).
ScenePlanSeeds seed_scene_plan(const inputs::LoadedScene& scene, const std::string& scene_path,
                               const std::string& fabric_path, pipeline::BakeRequest* request);

}  // namespace clothbake::reports

// The stages of a bake (docs/pipeline.md): the glue between the pipeline driver (bake/pipeline)
// and the algorithm libraries below it. Each stage reads named artifacts, calls one algorithm
// library and publishes its sections, metadata and artifacts for the stages after it.
//
// bake_stages() is the one list of the stages, in the order a full bake runs them; a stage is
// added by writing its factory below (one file per stage family in this folder) and putting it in
// that list (stage_list.cpp). The driver still derives the order from the declared inputs and
// outputs (plan_stages: a stage runs after the producers of its inputs, ties by name); a test
// (tests/bake/stages/test_stage_list.cpp) keeps the list equal to that order, so that the list
// never lies about when a stage runs.
#pragma once

#include <cstdint>
#include <vector>

#include "bake/pipeline/stage.hpp"

namespace clothbake::stages {

// Every stage of a bake, in run order: load_fabric, fabric_records, feature_maps, parallax,
// visibility, cluster, tables, compress, write.
std::vector<pipeline::Stage> bake_stages();

// The stages one by one, for tests and commands that run a few of them (each sets its name).
// fabric_stages.cpp: the fabric description in; its records and feature maps out.
pipeline::Stage load_fabric_stage();
pipeline::Stage fabric_records_stage();
pipeline::Stage feature_maps_stage();
// parallax_stage.cpp, visibility_stage.cpp (raycast/).
pipeline::Stage parallax_stage();
pipeline::Stage visibility_stage();
// cluster_stage.cpp (cluster/), tables_stage.cpp (tables/), compress_stage.cpp (compress/).
pipeline::Stage cluster_stage();
pipeline::Stage tables_stage();
pipeline::Stage compress_stage();
// write_stage.cpp: every section and metadata artifact in, the asset out (formats/writer).
pipeline::Stage write_stage();

// Optional seed of the compress stage (a compress::CompressRequest): what `clothbake bake
// --compress/--max-error/--keep-raw/--no-compress` asks; without it the stage follows the fabric's
// [bake] settings (compress::settings_from_bake).
inline constexpr const char* kCompressSettingsArtifact = "compress_options";
// Optional seed of the load_fabric stage (an int): `clothbake bake --resolution N`, the texels per
// tile side of a weave's generated maps instead of [bake] resolution (inputs::LoadOptions).
inline constexpr const char* kFabricResolutionArtifact = "fabric_resolution";
// What the compress stage supersedes (a std::vector<std::string> of section artifacts, read by
// the write stage): {"section/tables"} unless the raw tables are kept.
inline constexpr const char* kCompressSupersedesArtifact = "supersedes/compress";

// Optional seed of a scene-driven bake (`clothbake bake --scene`, docs/scene-plans.md): a
// PlannedBake. The parallax stage casts rays only for the kept view directions and writes a
// planned compressed parallax (kEntropyPlannedFlag); the tables and compress stages fill and
// compress only the kept half-vector bins (kCompressedPlannedFlag) and leave the gap kind out
// without transmission; the visibility stage samples visibility_dirs^2 light directions when the
// plan sets it (wide footprints, docs/scene-plans.md). The command seeds the bin_map / scene_plan
// sections and the plan's metadata itself ("section/scene_plan", "metadata/scene_plan").
inline constexpr const char* kScenePlanArtifact = "scene_plan";
struct PlannedBake {
  std::vector<uint8_t> half_vector_bins;  // radiance_dirs^2 entries, 1 = kept; empty: all bins
  std::vector<uint8_t> view_bins;         // parallax_dirs^2 entries, 1 = kept; empty: all
  bool transmission = true;               // false: the gap tables are left out
  int visibility_dirs = 0;  // light directions per side of the visibility sampling; 0: the fabric's
  // The parallax codes' RMS offset error in texels (reports::planned_parallax_error); 0: the
  // fabric's [bake] parallax_max_error.
  double parallax_max_error = 0;
};

}  // namespace clothbake::stages

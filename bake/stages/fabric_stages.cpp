// The stages that read the fabric description: load_fabric (bake/inputs: TOML, maps or weave,
// validation, input hashes) and the two that encode the fabric itself (fabric/fabric_sections.hpp):
// fabric_records (always: fabric info and yarn materials) and feature_maps (16-bit codes,
// entropy-coded by compress/map_entropy.hpp).
#include "bake/inputs/fabric_load.hpp"
#include "bake/stages/stages.hpp"
#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"

namespace clothbake::stages {
namespace {

void run_load_fabric(pipeline::StageContext& ctx) {
  LoadOptions options;
  if (ctx.has_input(kFabricResolutionArtifact))
    options.resolution = ctx.input<int>(kFabricResolutionArtifact);
  ctx.output("fabric",
             load_fabric_description(ctx.input<std::string>("fabric_path"), options).fabric);
}

void run_fabric_records(pipeline::StageContext& ctx) {
  ctx.output("section/fabric_records", fabric_record_sections(ctx.input<Fabric>("fabric")));
}

// The maps' 16-bit codes, entropy-coded (docs/format.md, "Feature maps").
void run_feature_maps(pipeline::StageContext& ctx) {
  ctx.output("section/feature_maps",
             compress::feature_map_sections(ctx.input<Fabric>("fabric").maps));
}

}  // namespace

pipeline::Stage load_fabric_stage() {
  pipeline::Stage s;
  s.name = "load_fabric";
  s.description = "read and validate the fabric description";
  s.inputs = {"fabric_path"};
  s.collects = {kFabricResolutionArtifact};
  s.outputs = {"fabric"};
  s.run = run_load_fabric;
  s.cacheable = false;  // reads files: its output is keyed by content instead
  return s;
}

pipeline::Stage fabric_records_stage() {
  pipeline::Stage s;
  s.name = "fabric_records";
  s.description = "fabric info and yarn material records";
  s.inputs = {"fabric"};
  s.outputs = {"section/fabric_records"};
  s.always = true;
  s.run = run_fabric_records;
  return s;
}

pipeline::Stage feature_maps_stage() {
  pipeline::Stage s;
  s.name = "feature_maps";
  s.description = "per-texel feature maps (height, tangent, normal, gap, yarn id, albedo)";
  s.inputs = {"fabric"};
  s.outputs = {"section/feature_maps"};
  s.run = run_feature_maps;
  return s;
}

}  // namespace clothbake::stages

// The stages that read the fabric description: load_fabric (bake/inputs: TOML, maps or weave,
// validation, input hashes) and the two that encode the fabric itself (fabric/fabric_sections.hpp):
// fabric_records (always: fabric info and yarn materials) and feature_maps (packed and
// entropy-coded by compress/map_entropy.hpp).
#include "bake/inputs/fabric_load.hpp"
#include "bake/stages/stages.hpp"
#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/map_encoding.hpp"

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

// The maps at reduced precision (payload version 2), each then entropy-coded (version 3) where
// that is smaller: both format 1.4, docs/format.md §6.4.
void run_feature_maps(pipeline::StageContext& ctx) {
  std::vector<formats::Section> sections = feature_map_sections(ctx.input<Fabric>("fabric").maps);
  // The tile's repeat shifts are searched once, on the height map (the first section), and
  // tried on every map's byte planes.
  compress::ShiftList shifts;
  bool searched = false;
  for (formats::Section& s : sections)
    if (s.version == reader::kFeatureMapPackedVersion) {
      s = compress::entropy_code_map(s, searched ? &shifts : nullptr, searched ? nullptr : &shifts);
      searched = true;
    }
  ctx.output("section/feature_maps", std::move(sections));
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

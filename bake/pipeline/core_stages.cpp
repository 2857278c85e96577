// The stages of the first bake (issue 4): load_fabric -> fabric_records, feature_maps -> write.
//
// This file is an INTERFACE source of clothbake_pipeline (see CMakeLists.txt and stage.hpp): it is
// compiled into every executable that links the library, so its registrations are never dropped.
#include <map>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/pipeline/stage.hpp"
#include "common/version.hpp"
#include "formats/reader/asset.hpp"
#include "formats/writer/asset_writer.hpp"
#include "formats/writer/atomic_file.hpp"
#include "fabric/fabric_sections.hpp"

namespace clothbake::pipeline::core_stages {
namespace {

using formats::Section;

void load_fabric_stage(StageContext& ctx) {
  ctx.output("fabric", load_fabric(ctx.input<std::string>("fabric_path")));
}

void fabric_records_stage(StageContext& ctx) {
  ctx.output("section/fabric_records",
             fabric_record_sections(ctx.input<Fabric>("fabric")));
}

void feature_maps_stage(StageContext& ctx) {
  ctx.output("section/feature_maps",
             feature_map_sections(ctx.input<Fabric>("fabric").maps));
}

// Metadata: provenance and parameters, deterministic unless timings are asked for.
nlohmann::json metadata(StageContext& ctx) {
  nlohmann::json m;
  m["format"] = "clothbake-asset";
  m["format_version"] =
      std::to_string(reader::kFormatMajor) + "." + std::to_string(reader::kFormatMinor);
  m["tool"] = {{"name", "clothbake"}, {"version", CLOTHBAKE_VERSION_STRING}};
  m["fabric"] = fabric_metadata(ctx.input<Fabric>("fabric"));
  m["stages"] = ctx.stage_order();
  nlohmann::json parameters = nlohmann::json::object();
  for (const auto& name : ctx.collected("metadata/"))
    parameters[name.substr(std::string("metadata/").size())] = ctx.input<nlohmann::json>(name);
  m["parameters"] = parameters;
  if (ctx.options().record_timings) {
    nlohmann::json timings = nlohmann::json::array();
    for (const auto& s : ctx.completed())
      timings.push_back({{"stage", s.name},
                         {"wall_seconds", s.wall_seconds},
                         {"cpu_seconds", s.cpu_seconds},
                         {"peak_rss_bytes", s.peak_rss_bytes}});
    m["timings"] = timings;
  }
  return m;
}

// Section artifacts that a stage replaces: every "supersedes/<stage>" artifact lists names of
// "section/..." artifacts that the write stage leaves out of the asset (the compress stage lists
// "section/tables" when the asset is to hold the compressed tables only). Name -> superseding
// artifact, sorted.
std::map<std::string, std::string> superseded_sections(StageContext& ctx) {
  std::map<std::string, std::string> out;
  for (const auto& name : ctx.collected("supersedes/"))
    for (const std::string& section : ctx.input<std::vector<std::string>>(name)) {
      if (section.rfind("section/", 0) != 0)
        throw_internal_error("artifact '" + name + "' supersedes '" + section +
                             "', which is not a section artifact");
      out.emplace(section, name.substr(std::string("supersedes/").size()));
    }
  return out;
}

void write_stage(StageContext& ctx) {
  const auto& request = ctx.input<OutputRequest>("output");
  const auto superseded = superseded_sections(ctx);
  // References to the sections the stages hold (no copy of the payloads: the raw tables alone can
  // be gigabytes).
  std::vector<const Section*> sections;
  nlohmann::json omitted = nlohmann::json::array();
  for (const auto& name : ctx.collected("section/")) {
    if (auto it = superseded.find(name); it != superseded.end()) {
      omitted.push_back({{"artifact", name}, {"superseded_by", it->second}});
      continue;
    }
    for (const Section& s : ctx.input<std::vector<Section>>(name))
      sections.push_back(&s);
  }
  nlohmann::json meta = metadata(ctx);
  if (!omitted.empty()) meta["omitted_sections"] = omitted;
  const Section metadata_section = formats::make_metadata_section(meta);
  sections.push_back(&metadata_section);

  formats::OutputOptions options;
  options.force = request.force;
  formats::write_asset_file(request.path, formats::SectionRefs(sections), options);

  // Summarise from the table order the writer used.
  AssetSummary summary;
  summary.path = request.path;
  summary.size_bytes = formats::asset_size(formats::SectionRefs(sections));
  reader::Asset asset;
  const reader::Status status = asset.open_file(request.path.c_str(), {reader::Verify::Structure});
  if (!status.ok())
    throw_internal_error(std::string("the asset just written does not open: ") + status.message());
  summary.content_hash = hex64(asset.content_hash());
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    reader::SectionInfo info;
    (void)asset.section(i, &info);
    SectionSummary s;
    const char* name = reader::section_type_name(info.type);
    s.name = name ? name : hex64(uint32_t(info.type)).substr(12);
    s.type = uint32_t(info.type);
    s.instance = info.instance;
    const char* element = reader::element_type_name(info.element_type);
    s.element = element ? element : "unknown";
    s.dims.assign(info.dims, info.dims + info.rank);
    s.offset = info.offset;
    s.bytes = info.stored_size;
    s.checksum = hex64(info.checksum);
    summary.sections.push_back(s);
  }
  ctx.progress(1.0);
  ctx.output("asset", std::move(summary));
}

}  // namespace
}  // namespace clothbake::pipeline::core_stages

using namespace clothbake::pipeline::core_stages;
using clothbake::pipeline::Stage;

CLOTHBAKE_REGISTER_STAGE(load_fabric) {
  Stage s;
  s.description = "read and validate the fabric description";
  s.inputs = {"fabric_path"};
  s.outputs = {"fabric"};
  s.run = load_fabric_stage;
  return s;
}

CLOTHBAKE_REGISTER_STAGE(fabric_records) {
  Stage s;
  s.description = "fabric info and yarn material records";
  s.inputs = {"fabric"};
  s.outputs = {"section/fabric_records"};
  s.always = true;
  s.run = fabric_records_stage;
  return s;
}

CLOTHBAKE_REGISTER_STAGE(feature_maps) {
  Stage s;
  s.description = "per-texel feature maps (height, tangent, normal, gap, yarn id, albedo)";
  s.inputs = {"fabric"};
  s.outputs = {"section/feature_maps"};
  s.run = feature_maps_stage;
  return s;
}

CLOTHBAKE_REGISTER_STAGE(write) {
  Stage s;
  s.description = "write the asset atomically (temporary file, fsync, rename)";
  s.inputs = {"fabric", "output"};
  s.collects = {"section/", "metadata/", "supersedes/"};
  s.outputs = {"asset"};
  s.always = true;
  s.run = write_stage;
  return s;
}

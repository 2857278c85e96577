// The `write` stage (always): collects every "section/*", "metadata/*" and "supersedes/*"
// artifact of the stages that ran, adds the metadata section (provenance, stage order, each
// stage's parameters) and writes the asset atomically through formats/writer; publishes the
// asset's summary ("asset", pipeline::AssetSummary) for the bake report. A file that already holds
// the exact bytes is not rewritten (AssetSummary::unchanged; docs/batch.md, "Restat").
#include <algorithm>
#include <map>

#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/error.hpp"
#include "common/version.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/writer/asset_writer.hpp"
#include "formats/writer/atomic_file.hpp"
#include "formats/writer/same_bytes.hpp"
#include "formats/writer/valid_asset.hpp"

namespace clothbake::stages {
namespace {

using formats::Section;
using pipeline::AssetSummary;
using pipeline::hex64;
using pipeline::OutputRequest;
using pipeline::SectionSummary;
using pipeline::StageContext;

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
  for (const auto& name : ctx.collected("metadata/")) {
    const nlohmann::json& value = ctx.input<nlohmann::json>(name);
    // Every stage writes an object; another type can only come from a crafted cache entry.
    if (!value.is_object()) throw_input_error("'" + name + "' is not a JSON object");
    parameters[name.substr(std::string("metadata/").size())] = value;
  }
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

// References to the sections the stages hold (no copy of the payloads: the raw tables alone can
// be gigabytes), in `sections`, the superseded ones named in `omitted`; returns the metadata.
nlohmann::json collect_sections(StageContext& ctx, std::vector<const Section*>* sections,
                                nlohmann::json* omitted) {
  const auto superseded = superseded_sections(ctx);
  for (const auto& name : ctx.collected("section/")) {
    if (auto it = superseded.find(name); it != superseded.end()) {
      omitted->push_back({{"artifact", name}, {"superseded_by", it->second}});
      continue;
    }
    for (const Section& s : ctx.input<std::vector<Section>>(name))
      sections->push_back(&s);
  }
  nlohmann::json meta = metadata(ctx);
  if (!omitted->empty()) meta["omitted_sections"] = *omitted;
  return meta;
}

void run_write(StageContext& ctx) {
  const auto& request = ctx.input<OutputRequest>("output");
  // Values from the cache are checked as values from a file: what this stage refuses of them, and
  // an asset assembled from them that does not validate, make the pipeline drop those entries and
  // recompute (pipeline::CachedValuesInvalid); costs one validation, only after cache hits.
  const bool from_cache = std::any_of(ctx.completed().begin(), ctx.completed().end(),
                                      [](const auto& s) { return s.cache == "hit"; });
  const auto refused = [&](const Error& e) {
    if (e.code() == ExitCode::Internal || !from_cache) throw;
    throw pipeline::CachedValuesInvalid("the write stage refused them: " + std::string(e.what()));
  };
  std::vector<const Section*> sections;
  nlohmann::json omitted = nlohmann::json::array();
  nlohmann::json meta;
  try {
    meta = collect_sections(ctx, &sections, &omitted);
  } catch (const pipeline::CacheEntryCorrupt&) {
    throw;
  } catch (const Error& e) {
    refused(e);
  }
  const Section metadata_section = formats::make_metadata_section(meta);
  sections.push_back(&metadata_section);

  formats::OutputOptions options;
  options.force = request.force;
  std::shared_ptr<formats::TempFile> pending;
  options.defer_commit = &pending;
  // Restat: an existing file with exactly these bytes is left alone (mtime kept).
  const bool unchanged = formats::file_holds_asset(request.path, formats::SectionRefs(sections));
  if (!unchanged) formats::write_asset_file(request.path, formats::SectionRefs(sections), options);
  const std::string written = pending ? pending->path().string() : request.path;
  if (from_cache) {
    try {
      (void)formats::open_valid_asset(written);
    } catch (const Error& e) {
      refused(e);
    }
  }
  if (pending && !request.defer_commit) {
    pending->commit();
    pending.reset();
  }
  const std::string summarised = pending ? pending->path().string() : request.path;

  // Summarise from the table order the writer used.
  AssetSummary summary;
  summary.path = request.path;
  summary.unchanged = unchanged;
  summary.pending = pending;
  summary.size_bytes = formats::asset_size(formats::SectionRefs(sections));
  // The structure and the header checksum the summary reports as the content hash (cheap: the
  // payloads were checked when they were written or, from the cache, validated above).
  reader::Asset asset;
  reader::Status status = asset.open_file(summarised.c_str());
  if (status.ok()) status = reader::verify_header_checksum(asset);

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

pipeline::Stage write_stage() {
  pipeline::Stage s;
  s.name = "write";
  s.description = "write the asset atomically (temporary file, fsync, rename)";
  s.inputs = {"fabric", "output"};
  s.collects = {"section/", "metadata/", "supersedes/"};
  s.outputs = {"asset"};
  s.always = true;
  s.run = run_write;
  s.cacheable = false;  // writes the asset
  return s;
}

}  // namespace clothbake::stages

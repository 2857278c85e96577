#include "bake/pipeline/bake.hpp"

#include <cstdio>

#include "common/diagnostics.hpp"
#include "common/version.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::pipeline {

std::string hex64(uint64_t value) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(value));
  return buf;
}

BakeResult bake(const BakeRequest& request, const std::vector<Stage>& stages) {
  formats::OutputOptions output;
  output.force = request.force;
  formats::check_output_path(request.output_path, output);

  Artifacts seeded;
  if (request.fabric)
    seeded.put("fabric", *request.fabric);
  else
    seeded.put("fabric_path", request.fabric_path);
  seeded.put("output", OutputRequest{request.output_path, request.force, request.defer_commit});
  seeded.merge(request.seeds);

  BakeResult result;
  result.run = run_pipeline(request.stages, std::move(seeded), request.run, stages);
  result.asset = result.run.artifacts.get<AssetSummary>("asset");
  return result;
}

nlohmann::json bake_report_json(const BakeRequest& request, const BakeResult& result) {
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& s : result.run.stages)
    stages.push_back({{"name", s.name},
                      {"wall_seconds", s.wall_seconds},
                      {"cpu_seconds", s.cpu_seconds},
                      {"peak_rss_bytes", s.peak_rss_bytes},
                      {"peak_rss_scope", s.peak_scope},
                      {"cache", s.cache}});
  nlohmann::json sections = nlohmann::json::array();
  for (const auto& s : result.asset.sections)
    sections.push_back({{"name", s.name},
                        {"type", s.type},
                        {"instance", s.instance},
                        {"element", s.element},
                        {"dims", s.dims},
                        {"offset", s.offset},
                        {"bytes", s.bytes},
                        {"xxh64", s.checksum}});
  nlohmann::json report;
  report["tool"] = {{"name", "clothbake"}, {"version", CLOTHBAKE_VERSION_STRING}};
  report["fabric"] = request.fabric ? request.fabric->name : request.fabric_path;
  report["threads"] = result.run.threads;
  report["stages"] = stages;
  report["total"] = {{"wall_seconds", result.run.wall_seconds},
                     {"cpu_seconds", result.run.cpu_seconds},
                     {"peak_rss_bytes", result.run.peak_rss_bytes}};
  report["asset"] = {{"path", result.asset.path},
                     {"size_bytes", result.asset.size_bytes},
                     {"content_hash", result.asset.content_hash},
                     {"unchanged", result.asset.unchanged},
                     {"sections", sections}};
  return report;
}

}  // namespace clothbake::pipeline

// Settings shared by the tables and compress stages (table_streaming.hpp).
#include "bake/stages/table_streaming.hpp"

#include "bake/stages/stages.hpp"
#include "fabric/fabric.hpp"

namespace clothbake::stages {

compress::CompressSettings compress_settings(const pipeline::StageContext& ctx) {
  const Fabric& fabric = ctx.input<Fabric>("fabric");
  return ctx.has_input(kCompressSettingsArtifact)
             ? compress::resolve_compress_settings(
                   fabric.bake, ctx.input<compress::CompressRequest>(kCompressSettingsArtifact))
             : compress::settings_from_bake(fabric.bake);
}

tables::RadianceOptions radiance_options(const Fabric& fabric) {
  tables::RadianceOptions options;
  options.bins_per_side = fabric.bake.radiance_dirs;
  return options;
}

tables::RadianceInputs StreamedTables::view() const {
  tables::RadianceInputs in;
  in.resolution = resolution;
  in.tangent = tangent;
  in.gap = gap;
  in.yarn_id = yarn_id;
  in.roughness = roughness;
  in.labels = labels;
  in.cluster_count = cluster_count;
  return in;
}

std::shared_ptr<const StreamedTables> make_streamed_tables(
    int resolution, std::vector<Vec3f> tangent, std::vector<float> gap,
    std::vector<uint16_t> yarn_id, std::vector<double> roughness, std::vector<uint8_t> labels,
    int cluster_count, const tables::RadianceOptions& options,
    tables::RadianceBuildReport* report) {
  auto out = std::make_shared<StreamedTables>();
  out->resolution = resolution;
  out->cluster_count = cluster_count;
  out->options = options;
  out->tangent = std::move(tangent);
  out->gap = std::move(gap);
  out->yarn_id = std::move(yarn_id);
  out->roughness = std::move(roughness);
  out->labels = std::move(labels);
  const tables::RadianceInputs in = out->view();
  for (const auto kind : {tables::RadianceTableKind::Specular, tables::RadianceTableKind::Gap}) {
    tables::QuantisedRadianceFill fill(
        kind, in, options, kind == tables::RadianceTableKind::Specular ? report : nullptr);
    if (!fill.empty()) out->fills.push_back(std::move(fill));
  }
  return out;
}

}  // namespace clothbake::stages

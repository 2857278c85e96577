// What the tables and compress stages share (docs/pipeline.md, "Streaming the tables into the
// compression"): the compression settings of this bake and, when only compressed tables are
// written, the streaming fill that replaces the raw SATs.
#pragma once

#include <memory>
#include <vector>

#include "bake/pipeline/stage.hpp"
#include "compress/compress_settings.hpp"
#include "tables/radiance_fill.hpp"

namespace clothbake::stages {

// The compress stage's settings: the fabric's [bake] settings overridden by the bake command's
// request (kCompressSettingsArtifact) when the stage collects it.
compress::CompressSettings compress_settings(const pipeline::StageContext& ctx);

// The fill options of the fabric's [bake] settings.
tables::RadianceOptions radiance_options(const Fabric& fabric);

// Artifact kStreamedTablesArtifact: the table sets as streaming fills, kinds ascending, only the
// non-empty ones. Null when the tables stage built the raw sets instead. It owns copies of the
// per-texel inputs the fills read (about 20 bytes a texel), so it stands alone: the fills' views
// point into its own vectors, and a cache can store and restore it (make_streamed_tables).
struct StreamedTables {
  int resolution = 0, cluster_count = 0;
  tables::RadianceOptions options;
  std::vector<Vec3f> tangent;
  std::vector<float> gap;
  std::vector<uint16_t> yarn_id;
  std::vector<double> roughness;
  std::vector<uint8_t> labels;
  std::vector<tables::QuantisedRadianceFill> fills;
  tables::RadianceInputs view() const;
};
// Copies the inputs and builds the fills (RadianceBuildReport of the specular fill in `report`).
// Errors as tables::QuantisedRadianceFill.
std::shared_ptr<const StreamedTables> make_streamed_tables(
    int resolution, std::vector<Vec3f> tangent, std::vector<float> gap,
    std::vector<uint16_t> yarn_id, std::vector<double> roughness, std::vector<uint8_t> labels,
    int cluster_count, const tables::RadianceOptions& options,
    tables::RadianceBuildReport* report = nullptr);
using StreamedTablesArtifact = std::shared_ptr<const StreamedTables>;
inline constexpr const char* kStreamedTablesArtifact = "tables/streamed";

}  // namespace clothbake::stages

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
// non-empty ones. Null when the tables stage built the raw sets instead.
struct StreamedTables {
  tables::FabricRadianceInputs inputs;  // owns the roughness list; maps and labels are views into
                                        // the "fabric" and "clusters" artifacts
  std::vector<tables::QuantisedRadianceFill> fills;
};
using StreamedTablesArtifact = std::shared_ptr<const StreamedTables>;
inline constexpr const char* kStreamedTablesArtifact = "tables/streamed";

}  // namespace clothbake::stages

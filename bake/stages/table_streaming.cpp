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

}  // namespace clothbake::stages

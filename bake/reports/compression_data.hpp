// The data `clothbake report compression` sweeps (bake/cli/cmd_report.cpp), in a library so that
// the compression studies (benchmarks/compress) can load the same data: one fabric's specular
// Integral-Radiance values as directional texels (compress/directional_texels.hpp), straight from
// the fill inputs, with the visibility clusters of the bake's own visibility and cluster stages.
//
// C++20. Errors: as load_fabric_description and the stages (Error with its exit code).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "compress/directional_texels.hpp"
#include "fabric/fabric.hpp"
#include "tables/radiance_fill.hpp"

namespace clothbake::reports {

struct CompressionData {
  Fabric fabric;
  std::vector<uint8_t> labels;          // visibility cluster per texel, row-major
  int clusters = 0;                     // visibility clusters
  std::string label_source;             // where the labels came from (the report's JSON)
  tables::FabricRadianceInputs inputs;  // the fill inputs (views into `fabric`; for raw tables)
  compress::DirectionalTexels data;     // the specular kind
};

// Loads FABRIC.toml at `resolution` texels per side (the fabric's own when empty) and computes its
// clusters and specular texel values. Held by pointer: `inputs` points into `fabric`.
std::unique_ptr<CompressionData> load_compression_data(const std::string& path,
                                                       std::optional<int> resolution);

}  // namespace clothbake::reports

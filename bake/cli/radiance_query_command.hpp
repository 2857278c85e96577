// The `radiance` kind of `clothbake query` (the command itself lives in bake/cli/cmd_query.cpp):
//
//   clothbake query ASSET radiance --lobe L [--cluster C] --h x,y,z --rect x0,y0,x1,y1 [--json]
//
// F_c(rect, h) of the lobe's Integral-Radiance table (formats/reader/radiance_query.hpp): the
// integral over the half-open texel rectangle (real corners, any size, wrapping over tiles) of
// the table values, bilinear over the 4 nearest half-vector bins, for one cluster or every
// cluster, with the footprint average and each cluster's share. Lobe names are those of
// `clothbake bsdf`; specular_reflection and specular_transmission read the shared specular table,
// delta_transmission the gap table; diffuse and sheen lobes have no table.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "eval/evaluator.hpp"
#include "formats/reader/asset.hpp"

namespace clothbake::cli {

struct RadianceQueryArgs {
  std::string lobe;
  std::optional<uint32_t> cluster;  // none: every cluster
  std::array<double, 3> h{0, 0, 1};
  std::array<double, 4> rect{0, 0, 1, 1};  // x0, y0, x1, y1
  // Which stored representation answers (options.hpp, --tables): Auto the compressed tables when
  // the asset has them, else the raw ones.
  eval::TableChoice source = eval::TableChoice::Auto;
};

// The answer as JSON ({lobe, table, source ("raw" or "compressed": which representation
// answered), h, rect, area, clusters: [{cluster, F, average}], total, total_average}). Errors
// (clothbake::Error): Usage for an unknown lobe, a lobe without a table, a cluster out of range, a
// bad h or rect (naming the option); Input when the asset lacks the table in the requested
// representation (a fabric without gaps has no delta_transmission table); InvalidAsset for
// malformed tables.
nlohmann::json radiance_query(const reader::Asset& asset, const RadianceQueryArgs& args);

// A short human-readable rendering of radiance_query's JSON.
std::string radiance_query_text(const nlohmann::json& answer);

}  // namespace clothbake::cli

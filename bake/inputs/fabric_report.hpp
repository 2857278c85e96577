// Reports about a loaded fabric: the JSON document of `clothbake inspect --json` (and the parts
// `clothbake pattern --json` shares) and the human-readable text of `clothbake inspect`.
// The JSON schema is documented in docs/fabric-format.md ("inspect --json").
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/map_stats.hpp"

namespace clothbake {

// Every resolved parameter (yarns, sheen, bake settings, tile size), defaults included.
nlohmann::json fabric_parameters_json(const Fabric& fabric);

// The weave of a weave-sourced fabric: label, picks, ends, matrix rows (rows = picks, columns =
// ends, '1' = warp on top), per-thread colours (linear RGB), yarn geometry; null for images.
nlohmann::json weave_json(const LoadedFabric& loaded);

// The whole inspect document: source, resolution, per-map origin and statistics, parameters,
// inputs with hashes, and `warnings`.
nlohmann::json inspect_json(const LoadedFabric& loaded, const inputs::MapStats& stats,
                            const std::vector<std::string>& warnings);

// The same content as text for a terminal.
std::string inspect_text(const LoadedFabric& loaded, const inputs::MapStats& stats,
                         const std::vector<std::string>& warnings);

}  // namespace clothbake

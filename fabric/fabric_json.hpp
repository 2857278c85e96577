// The one JSON form of a fabric's bake settings ([bake] of docs/fabric-format.md), shared by the
// asset's metadata (fabric_metadata, "fabric"."bake") and `clothbake inspect --json` ("bake"), so
// that the two cannot drift apart.
#pragma once

#include <nlohmann/json.hpp>

#include "fabric/fabric.hpp"

namespace clothbake {

// {"resolution", "parallax_dirs", "parallax_min_cos", "parallax_max_error", "visibility_dirs",
// "radiance_dirs", "clusters", "clusters_by_yarn", "visibility_rank", "compress",
// "compress_clusters", "compress_rank", "seed"}: every BakeSettings field under its [bake] key,
// unconverted. Deterministic (keys sorted, as nlohmann::json stores them).
nlohmann::json bake_settings_json(const BakeSettings& bake);

}  // namespace clothbake

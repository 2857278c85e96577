// Assets for the objects of a scene that name a fabric (`fabric = "f.toml"`), baked through the
// content-keyed stage cache (docs/batch.md, "Cache") and kept in its folder as finished assets
// (docs/scene-format.md, "Fabrics baked on the fly").
#pragma once

#include <string>

#include "bake/inputs/scene_load.hpp"

namespace clothbake::reports {

// The cache folder: `option` when given, else $CLOTHBAKE_CACHE, else $HOME/.cache/clothbake.
std::string scene_cache_dir(const std::string& option);

// For every objects[k] with fabrics[k] set: loads the fabric and keys its asset by the XXH3-128 of
// the tool and format versions, the cache schema and the loaded fabric's cache encoding (maps,
// yarns, sheen, resolved bake settings, input paths and content hashes). CACHE/assets/<stem>-<key>
// .cbk is used when it exists (its mtime refreshed: least recently used); otherwise the fabric is
// baked with the default stages and CACHE as the stage cache, so that a fabric whose edit only
// touches later stages (an albedo, a colour) reuses the ray casting, clustering and tables of an
// earlier bake. Sets objects[k].asset. Throws clothbake::Error (Input for a bad fabric or an
// unwritable cache folder).
// keep_raw_tables: bake (or reuse) the variant that also stores the raw tables and parallax codes
// (`bake --keep-raw`; 2.0 GB for the 256^2 twill, CACHE/assets/<stem>-<key>-raw.cbk), for comparing
// the compressed tables with the raw ones.
void bake_scene_fabrics(inputs::LoadedScene& scene, const std::string& cache_option, bool quiet,
                        bool keep_raw_tables = false);

}  // namespace clothbake::reports

// What the content-keyed cache (bake/cache, docs/batch.md) needs from the stages folder: the
// codecs of every artifact type the stages exchange, and the key views of the stages that read
// only part of an input.
#pragma once

#include "bake/cache/codec.hpp"
#include "bake/pipeline/artifacts.hpp"

namespace clothbake::stages {

// add_basic_codecs plus the algorithm types: visibility lobes (std::vector<AsgParams<float>>),
// cluster::VisibilityClusters, compress::CompressRequest.
cache::Codecs artifact_codecs();

// Key view (pipeline::Stage::key_view) of the stages whose outputs do not depend on the fabric's
// colours (the paper lets albedos and the sheen colour change without a rebake: parallax,
// visibility, cluster, tables, compress): the fabric with the albedo map, the yarn albedos and
// colours, the sheen, its name and its provenance cleared. Geometry, roughness, optical thickness
// and the bake settings stay.
void fabric_without_colours_view(const pipeline::Artifacts& available, pipeline::Artifacts& view);

}  // namespace clothbake::stages

// Typed access to the fabric sections of format 1.0: FabricInfo, YarnMaterials and the six
// per-texel feature maps (layout.hpp and docs/format.md define their payloads).
//
// C++17, standard library only, noexcept, no allocation; safe on any asset that open() accepted:
// each function checks the section's version, element type and shape before forming a view.
#pragma once

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

// Highest payload version of each section type this reader understands (0 if it does not
// interpret the type).
uint16_t known_section_version(SectionType type) noexcept;

// The feature maps of one N x N tile, row-major (texel (x, y) at y * N + x; row 0 is v = 0).
// Vector maps hold 3 floats per texel.
struct FeatureMapsView {
  uint32_t resolution = 0;      // N
  ArrayView<float> height;      // N*N, tile-side units
  ArrayView<float> tangent;     // N*N*3, unit, local frame
  ArrayView<float> normal;      // N*N*3, unit, local frame
  ArrayView<float> gap;         // N*N, I(x) in [0, 1]
  ArrayView<uint16_t> yarn_id;  // N*N, index into the yarn materials
  ArrayView<float> albedo;      // N*N*3, linear RGB
};

// All six maps; each must be version 1 with shape {N, N} or {N, N, 3} and one common N.
// Errors: NotFound (CBK-E019), Unsupported/WrongType (CBK-E015), Malformed (CBK-E016).
Status read_feature_maps(const Asset& asset, FeatureMapsView* out) noexcept;

// The single FabricInfo record. Errors: NotFound (CBK-E019), Unsupported/WrongType (CBK-E015).
Status read_fabric_info(const Asset& asset, const FabricInfoRecord** out) noexcept;

// The yarn material records (size = yarn count). Errors as read_fabric_info.
Status read_yarn_materials(const Asset& asset, ArrayView<YarnMaterialRecord>* out) noexcept;

}  // namespace clothbake::reader

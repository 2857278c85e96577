// Typed access to the fabric sections: FabricInfo, YarnMaterials and the six per-texel feature
// maps (layout.hpp, map_encoding.hpp and docs/format.md define their payloads).
//
// C++17, standard library only, noexcept; safe on any asset that open() accepted: each function
// checks the section's version, element type and shape before reading it. read_feature_maps is
// the only one that allocates (the decoded maps of payload version 2, with new (std::nothrow)).
#pragma once

#include <memory>

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

// Highest payload version of each section type this reader understands (0 if it does not
// interpret the type).
uint16_t known_section_version(SectionType type) noexcept;

// The feature maps of one N x N tile as floats, row-major (texel (x, y) at y * N + x; row 0 is
// v = 0). Vector maps hold 3 floats per texel, whatever the stored encoding. A map stored as f32
// (payload version 1, formats 1.0-1.3) is viewed in place in the asset (no copy); one stored at
// reduced precision (payload version 2, format 1.4: f16, octahedral snorm16, unorm16) is decoded
// into storage this object owns. So the views stay valid while both this object and the asset
// live. Move-only (moving keeps the views valid: the storage is on the heap).
struct FeatureMaps {
  uint32_t resolution = 0;      // N
  ArrayView<float> height;      // N*N, tile-side units
  ArrayView<float> tangent;     // N*N*3, unit, local frame
  ArrayView<float> normal;      // N*N*3, unit, local frame
  ArrayView<float> gap;         // N*N, I(x) in [0, 1]
  ArrayView<uint16_t> yarn_id;  // N*N, index into the yarn materials
  ArrayView<float> albedo;      // N*N*3, linear RGB
  // Payload version of each map as stored (height, tangent, normal, gap, yarn_id, albedo).
  uint16_t versions[6] = {};
  std::unique_ptr<float[]> storage;  // the decoded version-2 maps (null if all are version 1)

  FeatureMaps() = default;
  FeatureMaps(FeatureMaps&&) noexcept = default;
  FeatureMaps& operator=(FeatureMaps&&) noexcept = default;
  FeatureMaps(const FeatureMaps&) = delete;
  FeatureMaps& operator=(const FeatureMaps&) = delete;
};

// All six maps, decoded to floats; one common N. Each map is payload version 1 (f32 {N, N} or
// {N, N, 3}; yarn_id u16 {N, N}) or version 2 (map_encoding.hpp: height f16 {N, N}, tangent and
// normal i16 {N, N, 2} octahedral, gap u16 {N, N} and albedo u16 {N, N, 3} unorm16); yarn_id has
// version 1 only. Decoding checks nothing beyond shapes (a NaN f16 height decodes to NaN, as a NaN
// f32 one is viewed): validate_asset checks the values. Errors: NotFound (CBK-E019),
// Unsupported/WrongType (CBK-E015), Malformed (CBK-E016), Unsupported with Check::ResourceLimit
// (CBK-E024) when the decoded maps cannot be allocated. On error *out is left unchanged.
Status read_feature_maps(const Asset& asset, FeatureMaps* out) noexcept;

// The single FabricInfo record. Errors: NotFound (CBK-E019), Unsupported/WrongType (CBK-E015).
Status read_fabric_info(const Asset& asset, const FabricInfoRecord** out) noexcept;

// The yarn material records (size = yarn count). Errors as read_fabric_info.
Status read_yarn_materials(const Asset& asset, ArrayView<YarnMaterialRecord>* out) noexcept;

}  // namespace clothbake::reader

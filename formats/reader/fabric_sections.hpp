// Typed access to the fabric sections: FabricInfo, YarnMaterials and the six per-texel feature
// maps (layout.hpp, map_encoding.hpp and docs/format.md define their payloads).
//
// C++17, standard library only, noexcept; safe on any asset that open() accepted: each function
// checks the section's version, element type and shape before reading it. read_feature_maps
// allocates (the decoded maps and their scratch, with new (std::nothrow)); the others do not.
#pragma once

#include <memory>

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

// Highest payload version of each section type this reader understands (0 if it does not
// interpret the type).
uint16_t known_section_version(SectionType type) noexcept;

// The feature maps of one N x N tile as floats, row-major (texel (x, y) at y * N + x; row 0 is
// v = 0). Vector maps hold 3 floats per texel. The five coded maps are decoded into storage this
// object owns; yarn_id is viewed in place in the asset. So the views stay valid while both this
// object and the asset live. Move-only (moving keeps the views valid: the storage is on the heap).
struct FeatureMaps {
  uint32_t resolution = 0;       // N
  ArrayView<float> height;       // N*N, tile-side units
  ArrayView<float> tangent;      // N*N*3, unit, local frame
  ArrayView<float> normal;       // N*N*3, unit, local frame
  ArrayView<float> gap;          // N*N, I(x) in [0, 1]
  ArrayView<uint16_t> yarn_id;   // N*N, index into the yarn materials
  ArrayView<float> albedo;       // N*N*3, linear RGB
  model::Buffer<float> storage;  // the decoded maps

  FeatureMaps() = default;
  FeatureMaps(FeatureMaps&&) noexcept = default;
  FeatureMaps& operator=(FeatureMaps&&) noexcept = default;
  FeatureMaps(const FeatureMaps&) = delete;
  FeatureMaps& operator=(const FeatureMaps&) = delete;
};

// All six maps, decoded to floats; one common N. Height, tangent, normal, gap and albedo are u8
// {bytes}: their 16-bit codes (map_encoding.hpp: f16 height, octahedral snorm16 tangent and
// normal, unorm16 gap and albedo) entropy-coded (map_entropy.hpp); yarn_id is u16 {N, N}.
// Decoding checks the coding and the shapes, not the values (a NaN f16 height decodes to NaN):
// validate_asset checks the values. Thread-safe (no shared state). Errors: NotFound (CBK-E019),
// Unsupported/WrongType (CBK-E015), Malformed (CBK-E016: resolutions differ; CBK-E021: a coding
// fault, naming the map and byte plane), Unsupported with Check::ResourceLimit (CBK-E024) when
// the decoded maps cannot be allocated. On error *out is left unchanged.
Status read_feature_maps(const Asset& asset, FeatureMaps* out) noexcept;

// The single FabricInfo record. Errors: NotFound (CBK-E019), Unsupported/WrongType (CBK-E015).
Status read_fabric_info(const Asset& asset, const FabricInfoRecord** out) noexcept;

// The yarn material records (size = yarn count). Errors as read_fabric_info.
Status read_yarn_materials(const Asset& asset, ArrayView<YarnMaterialRecord>* out) noexcept;

}  // namespace clothbake::reader

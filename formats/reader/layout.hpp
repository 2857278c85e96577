// On-disk layout of the clothbake asset container, format version 2 (docs/format.md is the
// specification; this header is its machine-checked summary).
//
// Everything is little-endian. A file is: a 64-byte FileHeader at offset 0, the section table
// (section_count entries of section_entry_size bytes, starting at offset 64), then the section
// payloads, each at an offset that is a multiple of 64, zero-padded in between and up to
// FileHeader::file_size (a multiple of 64).
//
// C++17, standard library only: this header is part of the reader library (clothbake::reader).
#pragma once

#include <cstddef>
#include <cstdint>

namespace clothbake::reader {

// ---------------------------------------------------------------------------------------------
// Format version. The major number is the on-disk layout: a reader refuses any other major (a
// format-1 asset is re-baked, docs/format.md "Versioning"). The minor number grows when section
// types, codecs or element types are added in a way that an older reader can skip; an older
// reader reads a newer minor and ignores what it does not know. Format 2.0 has one form per
// section, every payload at version 1.
inline constexpr uint16_t kFormatMajor = 2;
inline constexpr uint16_t kFormatMinor = 0;

// "\x89CBK\r\n\x1a\n": the high byte catches 7-bit transfers, CR LF / LF catch newline conversion,
// ^Z stops `type` on DOS (the PNG signature idea).
inline constexpr unsigned char kMagic[8] = {0x89, 'C', 'B', 'K', '\r', '\n', 0x1a, '\n'};

inline constexpr uint64_t kSectionAlignment = 64;  // payload offsets and file_size
inline constexpr uint32_t kMinSectionEntrySize = 64;
inline constexpr uint32_t kMaxSectionCount = 1u << 20;  // bounds the table (64 MiB at 64 B/entry)
inline constexpr uint32_t kMaxRank = 4;

// ---------------------------------------------------------------------------------------------
// Section types. Ids are grouped by producer, 256 ids per group; an id is never reused for a
// different payload. Unknown ids are skipped by readers.
enum class SectionType : uint32_t {
  // Container.
  Metadata = 0x0001,       // UTF-8 JSON object: tool, bake parameters, input hashes, stages
  FabricInfo = 0x0002,     // one FabricInfoRecord
  YarnMaterials = 0x0003,  // YarnMaterialRecord[yarn_count]
  // Per-texel feature maps of one N x N tile, row-major, row 0 is v = 0: 16-bit codes,
  // entropy-coded (map_entropy.hpp), except yarn_id.
  HeightMap = 0x0100,   // f16 codes, tile-side units
  TangentMap = 0x0101,  // octahedral snorm16 codes of the unit fibre tangent, local frame
  NormalMap = 0x0102,   // octahedral snorm16 codes of the unit shading normal, z > 0
  GapMap = 0x0103,      // unorm16 codes of I(x) in [0, 1]
  YarnIdMap = 0x0104,   // u16 {N, N}, index into YarnMaterials
  AlbedoMap = 0x0105,   // unorm16 codes of linear RGB in [0, 1]
  // Baked tables; their payload layout is defined where they are read.
  ParallaxTable = 0x0200,  // raw parallax depth codes per view direction and texel
  ParallaxSat = 0x0201,    // summed-area tables of the raw codes
  // 0x0202: retired (parallax_compressed of formats 1.1-1.4), never reused.
  ParallaxEntropy = 0x0203,         // hierarchical entropy-coded parallax (parallax_hierarchy.hpp)
  VisibilityAsg = 0x0300,           // per-texel ASG visibility parameters
  AsgFitError = 0x0301,             // per-texel ASG fit error
  ClusterLabels = 0x0400,           // visibility cluster label map
  ClusterMeanVisibility = 0x0401,   // per-cluster mean visibility
  ClusterVisibilityBasis = 0x0402,  // per-cluster principal components of the visibility
  RadianceRawTables = 0x0500,       // Integral-Radiance SATs (lobe, cluster, half-vector bin)
  RadianceCompressedTables = 0x0501,  // C-PCA compressed Integral-Radiance tables
  // 0x0502..0x05FF: reserved for parts of the compressed tables (basis, means, quantisation).
  // Scene-planned assets (scene_plan_sections.hpp).
  BinMap = 0x0600,     // u8 {n, n} per direction grid: 1 = bin covered by the asset
  ScenePlan = 0x0601,  // one ScenePlanRecord: what a scene-driven bake left out
  // 0x0602: retired (parallax_planned of format 1.2), never reused.
  // 0x8000..0xFFFF: never assigned by clothbake; free for experiments and private extensions.
};

// How the stored bytes encode the payload. Only Raw is written.
enum class Codec : uint16_t {
  Raw = 0,
  Zstd = 1,  // reserved; never written, not decodable by this reader
};

// Element type of a typed-array payload. Opaque means the payload has its own layout (rank 0).
enum class ElementType : uint16_t {
  Opaque = 0,
  U8 = 1,
  I8 = 2,
  U16 = 3,
  I16 = 4,
  U32 = 5,
  I32 = 6,
  U64 = 7,
  I64 = 8,
  F16 = 9,  // IEEE 754 binary16
  F32 = 10,
  F64 = 11,
};

// Bytes per element, 0 for Opaque and unknown types.
constexpr uint32_t element_size(ElementType type) {
  switch (type) {
    case ElementType::U8:
    case ElementType::I8:
      return 1;
    case ElementType::U16:
    case ElementType::I16:
    case ElementType::F16:
      return 2;
    case ElementType::U32:
    case ElementType::I32:
    case ElementType::F32:
      return 4;
    case ElementType::U64:
    case ElementType::I64:
    case ElementType::F64:
      return 8;
    case ElementType::Opaque:
      return 0;
  }
  return 0;
}

// ---------------------------------------------------------------------------------------------
// File header: 64 bytes at offset 0. Bytes 0..11 (magic and version) keep this meaning in every
// future major version, so that any reader can say which side is too old.
struct FileHeader {
  unsigned char magic[8];       // kMagic
  uint16_t version_major;       // kFormatMajor
  uint16_t version_minor;       // kFormatMinor of the writer
  uint32_t section_count;       // entries in the table, <= kMaxSectionCount
  uint32_t section_entry_size;  // >= 64, multiple of 8; readers use the first 64 bytes
  uint32_t flags;               // 0 in 1.0; readers ignore bits they do not know
  uint64_t file_size;           // total bytes, multiple of 64
  unsigned char reserved[24];   // zero
  // XXH64 (seed 0) of bytes [0, 56) followed by the whole section table. As the table holds the
  // checksum of every payload, this identifies the asset's content.
  uint64_t header_checksum;
};

static_assert(sizeof(FileHeader) == 64, "FileHeader must be 64 bytes");
static_assert(alignof(FileHeader) == 8, "FileHeader alignment");
static_assert(offsetof(FileHeader, magic) == 0);
static_assert(offsetof(FileHeader, version_major) == 8);
static_assert(offsetof(FileHeader, version_minor) == 10);
static_assert(offsetof(FileHeader, section_count) == 12);
static_assert(offsetof(FileHeader, section_entry_size) == 16);
static_assert(offsetof(FileHeader, flags) == 20);
static_assert(offsetof(FileHeader, file_size) == 24);
static_assert(offsetof(FileHeader, reserved) == 32);
static_assert(offsetof(FileHeader, header_checksum) == 56);
inline constexpr std::size_t kHeaderChecksumOffset = offsetof(FileHeader, header_checksum);

// One entry of the section table (the first 64 bytes of each entry).
struct SectionEntry {
  uint32_t type;          // SectionType
  uint16_t version;       // payload layout version of this section type (starts at 1)
  uint16_t codec;         // Codec
  uint64_t offset;        // payload offset from the start of the file, multiple of 64
  uint64_t stored_size;   // bytes stored at offset
  uint64_t checksum;      // XXH64 (seed 0) of the stored bytes
  uint64_t raw_size;      // bytes after decoding; == stored_size for Codec::Raw
  uint16_t element_type;  // ElementType
  uint16_t rank;          // number of used dims, 0..4 (0 only for Opaque)
  uint32_t dims[4];       // shape, slowest-varying first (C order); unused dims are 0
  uint32_t instance;      // tells apart sections of one type (e.g. a lobe index); 0 if single
};

static_assert(sizeof(SectionEntry) == 64, "SectionEntry must be 64 bytes");
static_assert(alignof(SectionEntry) == 8, "SectionEntry alignment");
static_assert(offsetof(SectionEntry, type) == 0);
static_assert(offsetof(SectionEntry, version) == 4);
static_assert(offsetof(SectionEntry, codec) == 6);
static_assert(offsetof(SectionEntry, offset) == 8);
static_assert(offsetof(SectionEntry, stored_size) == 16);
static_assert(offsetof(SectionEntry, checksum) == 24);
static_assert(offsetof(SectionEntry, raw_size) == 32);
static_assert(offsetof(SectionEntry, element_type) == 40);
static_assert(offsetof(SectionEntry, rank) == 42);
static_assert(offsetof(SectionEntry, dims) == 44);
static_assert(offsetof(SectionEntry, instance) == 60);

// ---------------------------------------------------------------------------------------------
// Payload records (section version 1). Records are stored as U8 arrays of shape
// {count, sizeof(record)}, so that the generic size checks apply to them too.

// FabricInfo v1: one record, shape {1, 64}.
struct FabricInfoRecord {
  uint32_t resolution;         // N, texels per tile side of the feature maps (0 if none stored)
  uint32_t yarn_count;         // records in YarnMaterials
  double sheen_color[3];       // sheen albedo scale (linear RGB); zero disables sheen
  double sheen_roughness;      // (0, 1]
  double tile_size_mm;         // physical tile width (along u) in mm; 0 if unknown
  unsigned char reserved[16];  // zero
};

static_assert(sizeof(FabricInfoRecord) == 64);
static_assert(alignof(FabricInfoRecord) == 8);
static_assert(offsetof(FabricInfoRecord, resolution) == 0);
static_assert(offsetof(FabricInfoRecord, yarn_count) == 4);
static_assert(offsetof(FabricInfoRecord, sheen_color) == 8);
static_assert(offsetof(FabricInfoRecord, sheen_roughness) == 32);
static_assert(offsetof(FabricInfoRecord, tile_size_mm) == 40);
static_assert(offsetof(FabricInfoRecord, reserved) == 48);

inline constexpr std::size_t kYarnNameBytes = 32;

// YarnMaterials v1: shape {yarn_count, 160}; the paper's Sec. 3 parameters of one yarn.
struct YarnMaterialRecord {
  char name[kYarnNameBytes];        // UTF-8, NUL-terminated and NUL-padded (<= 31 bytes)
  double roughness;                 // SGGX fibre roughness, (0, 1]
  double optical_thickness;         // SpongeCake optical thickness T, > 0
  double specular_albedo[3];        // linear RGB
  double diffuse_reflectance[3];    // linear RGB
  double diffuse_transmittance[3];  // linear RGB
  double color[3];                  // linear RGB
  unsigned char reserved[16];       // zero
};

static_assert(sizeof(YarnMaterialRecord) == 160);
static_assert(alignof(YarnMaterialRecord) == 8);
static_assert(offsetof(YarnMaterialRecord, name) == 0);
static_assert(offsetof(YarnMaterialRecord, roughness) == 32);
static_assert(offsetof(YarnMaterialRecord, optical_thickness) == 40);
static_assert(offsetof(YarnMaterialRecord, specular_albedo) == 48);
static_assert(offsetof(YarnMaterialRecord, diffuse_reflectance) == 72);
static_assert(offsetof(YarnMaterialRecord, diffuse_transmittance) == 96);
static_assert(offsetof(YarnMaterialRecord, color) == 120);
static_assert(offsetof(YarnMaterialRecord, reserved) == 144);

// ---------------------------------------------------------------------------------------------
// Naming (for messages, `clothbake info` and `export --section NAME`).

// Short lower-case name of a section type ("height", "yarn_materials"), or nullptr if unknown.
const char* section_type_name(SectionType type) noexcept;
#ifndef CLOTHBAKE_SINGLE_FILE  // for command lines
// Inverse of section_type_name; returns false if the name is unknown.
bool section_type_from_name(const char* name, SectionType* out) noexcept;
#endif
// "u8", "f32", ... or nullptr if unknown.
const char* element_type_name(ElementType type) noexcept;
// "raw", "zstd", or nullptr if unknown.
const char* codec_name(Codec codec) noexcept;
// "section #3 (height, instance 0)", or with "type 0x8001" for an unknown type, into buf (cap
// bytes, truncated and NUL-terminated; cap > 0); returns buf. For messages.
const char* describe_section(char* buf, std::size_t cap, uint32_t index, uint32_t type,
                             uint32_t instance) noexcept;

}  // namespace clothbake::reader

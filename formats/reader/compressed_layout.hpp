// On-disk layout of the C-PCA compressed Integral-Radiance tables (paper Sec. 4.4;
// docs/compression.md explains every choice and the measurements behind it).
//
// What is compressed. One table kind (radiance_layout.hpp) is, per texel x, a directional vector
// T(x, .) over the B = n * n half-vector bins, and texel x contributes to exactly one visibility
// cluster c(x) (the raw layout's per-cluster tables are masks of one texel x bin matrix). The
// texels of each cluster are split into cells (C-PCA clusters nested in the visibility cluster);
// a cell g approximates its texels' vectors by its mean plus a rank-r_g basis:
//
//   T(x, b) ~ sum over images i of cell g(x):  w_i(x) * scale[i] * basis[i][b]
//
// where cell g owns images first_image .. first_image + r_g: image 0 is the mean (weight
// w = 1 on the cell's texels), image j >= 1 the j-th basis vector (weight w = q_j(x), the texel's
// j-th quantised coefficient). A footprint query is linear, so
//
//   F_c(R, b) = sum over cells g of cluster c, images i of g:  W_i(R) * scale[i] * basis[i][b]
//
// with W_i(R) the integral of w_i over the footprint: one summed-area table per image, built by
// the reader at open time from the per-texel weights (exact integer prefix sums), never stored.
// Texels without a cell (their vector is zero, e.g. the gaps in the specular kind) contribute 0.
//
// Sections of one kind K (type RadianceCompressedTables, instance = K * 16 + part), version 1:
//   part 0 Info   : u8 {1, 64}   one CompressedTableInfoRecord
//   part 1 Cells  : u32 {G, 4}   per cell: cluster id, rank r_g, texel count, first image;
//                                cluster ids non-decreasing; first_image = sum of (1 + r) before
//   part 2 CellMap: u8 {N, N}    cell of each texel (row-major), kNoCell for none
//   part 3 Scales : f32 {I}      per image: finite, >= 0 (I = sum over cells of 1 + r_g)
//   part 4 Basis  : f16 {I, B}   per image: the directional vector, max |value| = 1 (or all 0)
//   part 5 Coeffs : u8 {bytes}   for every texel in row-major order, the r_{g(x)} quantised i16
//                                coefficients of its cell (none for kNoCell), M in all,
//                                entropy-coded (compressed_coefficients.hpp)
// A scene-planned kind (info flags kCompressedPlannedFlag) stores only the half-vector bins of
// bin_map instance 0: the basis values of the other bins are zero, and queries that need them
// answer OutOfPlan.
//
// C++17, standard library only (part of the reader library).
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/radiance_layout.hpp"

namespace clothbake::reader {

enum class CompressedPart : uint32_t {
  Info = 0,
  Cells = 1,
  CellMap = 2,
  Scales = 3,
  Basis = 4,
  Coefficients = 5  // entropy-coded (compressed_coefficients.hpp)
};
inline constexpr uint32_t kCompressedPartCount = 6;
// CompressedTableInfoRecord::flags bit of a scene-planned kind (bins of bin_map instance 0 only).
inline constexpr uint32_t kCompressedPlannedFlag = 1;

constexpr uint32_t compressed_instance(RadianceTableKind kind, CompressedPart part) {
  return uint32_t(kind) * 16u + uint32_t(part);
}

inline constexpr uint8_t kNoCell = 255;
inline constexpr uint32_t kMaxCompressedCells = 255;    // cell ids 0..254 (u8 map, 255 = none)
inline constexpr uint32_t kMaxCompressedRank = 255;     // basis vectors per cell
inline constexpr uint32_t kMaxCompressedImages = 4096;  // bounds the reader's SAT memory
// Largest decoded form (integer SATs, (N + 1)^2 x images x 4 or 8 bytes) a reader builds for one
// table; open() refuses a larger one with CBK-E024 before allocating anything.
inline constexpr uint64_t kMaxCompressedDecodedBytes = uint64_t(2) << 30;
inline constexpr uint32_t kCellFields = 4;

// Info: one record, shape {1, 64}.
struct CompressedTableInfoRecord {
  uint32_t kind;                  // RadianceTableKind
  uint32_t resolution;            // N (= the label map's)
  uint32_t bins_per_side;         // n (1 for Gap)
  uint32_t cluster_count;         // clusters of the label map
  uint32_t cell_count;            // G, rows of Cells
  uint32_t image_count;           // I, sum over cells of 1 + r_g
  uint32_t coefficient_count;     // M, coefficients coded in Coeffs
  uint32_t samples_per_bin_side;  // s of the raw tables this was compressed from (0 for Gap)
  uint32_t lobes;                 // kLobeBit* of the lobes this table answers
  uint32_t flags;                 // 0, or kCompressedPlannedFlag
  double min_roughness;           // narrowest SGGX roughness in the map (0 for Gap)
  double bake_error;              // relative RMS texel error measured at bake time (information)
  unsigned char reserved[8];      // zero
};

static_assert(sizeof(CompressedTableInfoRecord) == 64);
static_assert(alignof(CompressedTableInfoRecord) == 8);
static_assert(offsetof(CompressedTableInfoRecord, kind) == 0);
static_assert(offsetof(CompressedTableInfoRecord, resolution) == 4);
static_assert(offsetof(CompressedTableInfoRecord, bins_per_side) == 8);
static_assert(offsetof(CompressedTableInfoRecord, cluster_count) == 12);
static_assert(offsetof(CompressedTableInfoRecord, cell_count) == 16);
static_assert(offsetof(CompressedTableInfoRecord, image_count) == 20);
static_assert(offsetof(CompressedTableInfoRecord, coefficient_count) == 24);
static_assert(offsetof(CompressedTableInfoRecord, samples_per_bin_side) == 28);
static_assert(offsetof(CompressedTableInfoRecord, lobes) == 32);
static_assert(offsetof(CompressedTableInfoRecord, flags) == 36);
static_assert(offsetof(CompressedTableInfoRecord, min_roughness) == 40);
static_assert(offsetof(CompressedTableInfoRecord, bake_error) == 48);
static_assert(offsetof(CompressedTableInfoRecord, reserved) == 56);

// One row of Cells.
struct CompressedCell {
  uint32_t cluster;      // visibility cluster id, < cluster_count
  uint32_t rank;         // r_g <= kMaxCompressedRank
  uint32_t texels;       // texels whose CellMap entry is this cell
  uint32_t first_image;  // index of the cell's mean image
};
static_assert(sizeof(CompressedCell) == 16);

}  // namespace clothbake::reader

// On-disk layout of the raw Integral-Radiance tables (paper Sec. 4.3; docs/tables.md has the full
// specification and the reasoning behind every choice).
//
// Which tables exist ("table kinds"). With Eq. 4's I(x) factor, the base term of both specular
// lobes integrates I(x) D(x, h) over the footprint, each over its own half vector: reflection and
// transmission share one table (SGGX is centrally symmetric, so h and -h fold to the same bin),
// indexed by the folded half vector. The delta-transmission lobe integrates (1 - I(x)) and has no
// h dependence: one table with a single bin. Diffuse and sheen lobes need no table here.
//
//   kind Specular (0): T[c][b](x) = I(x) * (bin average of D(x, h) over half-vector bin b)
//                      * [label(x) = c];  bins: DirectionGrid{n, 0} on the folded upper hemisphere;
//                      answers specular_reflection and specular_transmission.
//   kind Gap      (1): T[c][0](x) = (1 - I(x)) * [label(x) = c];  one bin; answers
//                      delta_transmission. Not stored when no texel has I(x) < 1.
//
// Storage: exact fixed-point summed-area tables. For each (bin b, stored cluster column k) the
// texel values are quantised to integers q = round(T / unit[b][k]) with unit chosen so that the
// whole tile sums to less than 2^32 (u32 tables) or 2^62 (u64 tables); the SAT of the integers is
// then exact (integer additions), every rectangle sum is exact up to the quantisation of its texels
// (at most unit / 2 each), and the error does not grow with the position in the table. u32 is used
// when the bound N^2 / 2^33 (error relative to the table's mean texel value) meets the bake's
// precision target, else u64 (docs/tables.md, "Precision").
//
// Sections of one kind K (instance = K * 16 + part), all section version 1:
//   part 0 Info     : u8 {1, 64}          one RadianceTableInfoRecord
//   part 1 Clusters : u32 {C}             stored cluster ids, strictly ascending, < cluster_count
//                                         (clusters without a non-zero texel are not stored)
//   part 2 Units    : f64 {B, C}          value of one integer step of (bin, column), finite > 0
//   part 3 Sat      : u32|u64 {B, N, N, C} inclusive SATs, interleaved by cluster:
//                     Sat[b][y][x][k] = sum over y' <= y, x' <= x of q_{b,k}(x', y')
// where B = n * n half-vector bins (bin index j * n + i of model/directions.hpp), N the map
// resolution, C the stored clusters. Interleaving the clusters puts the values every cluster needs
// at one footprint corner in one cache line: a renderer sums over all clusters (Eq. 8).
//
// C++17, standard library only (part of the reader library).
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/layout.hpp"

namespace clothbake::reader {

enum class RadianceTableKind : uint32_t {
  Specular = 0,  // I(x) D(x, h): specular_reflection, specular_transmission
  Gap = 1,       // 1 - I(x): delta_transmission
};
inline constexpr uint32_t kRadianceKindCount = 2;

enum class RadiancePart : uint32_t { Info = 0, Clusters = 1, Units = 2, Sat = 3 };

// Section instance of one part of one kind's tables.
constexpr uint32_t radiance_instance(RadianceTableKind kind, RadiancePart part) {
  return uint32_t(kind) * 16u + uint32_t(part);
}

// Lobe bits of RadianceTableInfoRecord::lobes (bit = model::Lobe value, docs/model.md order).
inline constexpr uint32_t kLobeBitSpecularReflection = 1u << 0;
inline constexpr uint32_t kLobeBitSpecularTransmission = 1u << 1;
inline constexpr uint32_t kLobeBitDeltaTransmission = 1u << 4;

// Largest number of visibility clusters (labels are u8).
inline constexpr uint32_t kMaxRadianceClusters = 255;
// Largest half-vector grid side and map resolution a reader accepts (bounds every product).
inline constexpr uint32_t kMaxRadianceBinsPerSide = 256;
inline constexpr uint32_t kMaxRadianceResolution = 16384;

// Info v1: one record, shape {1, 64}.
struct RadianceTableInfoRecord {
  uint32_t kind;                  // RadianceTableKind
  uint32_t resolution;            // N, texels per tile side (= the label map's)
  uint32_t bins_per_side;         // n (1 for Gap)
  uint32_t cluster_count;         // clusters of the label map (ids 0 .. cluster_count - 1)
  uint32_t stored_clusters;       // C, columns of Units and Sat
  uint32_t element_bits;          // 32 (Sat is u32) or 64 (u64)
  uint32_t samples_per_bin_side;  // s: s x s stratified half vectors per bin (0 for Gap)
  uint32_t lobes;                 // kLobeBit* of the lobes this table answers
  double min_roughness;           // narrowest SGGX roughness in the map (0 for Gap)
  double precision_target;        // the relative error the element type was chosen for
  unsigned char reserved[16];     // zero
};

static_assert(sizeof(RadianceTableInfoRecord) == 64);
static_assert(alignof(RadianceTableInfoRecord) == 8);
static_assert(offsetof(RadianceTableInfoRecord, kind) == 0);
static_assert(offsetof(RadianceTableInfoRecord, resolution) == 4);
static_assert(offsetof(RadianceTableInfoRecord, bins_per_side) == 8);
static_assert(offsetof(RadianceTableInfoRecord, cluster_count) == 12);
static_assert(offsetof(RadianceTableInfoRecord, stored_clusters) == 16);
static_assert(offsetof(RadianceTableInfoRecord, element_bits) == 20);
static_assert(offsetof(RadianceTableInfoRecord, samples_per_bin_side) == 24);
static_assert(offsetof(RadianceTableInfoRecord, lobes) == 28);
static_assert(offsetof(RadianceTableInfoRecord, min_roughness) == 32);
static_assert(offsetof(RadianceTableInfoRecord, precision_target) == 40);
static_assert(offsetof(RadianceTableInfoRecord, reserved) == 48);

// "specular" / "gap", or nullptr.
const char* radiance_kind_name(RadianceTableKind kind) noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
// The table kind that answers a lobe name of `clothbake bsdf` ("specular_reflection",
// "specular_transmission" -> Specular; "delta_transmission" -> Gap). False for lobes without an
// Integral-Radiance table (diffuse_*, sheen) and unknown names.
bool radiance_kind_of_lobe(const char* lobe_name, RadianceTableKind* out) noexcept;
#endif

}  // namespace clothbake::reader

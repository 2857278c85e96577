// Scene-planned assets (docs/format.md, "Scene-planned assets"): a bake driven by a scene
// (`clothbake bake F.toml --scene S.toml`) keeps only what the scene can query. Two section types
// say what was kept:
//
//   BinMap instance g: u8 {n, n}     entry [j][i] = 1 when bin (i, j) (index j * n + i) of
//                                    direction grid g is covered by the asset, 0 when it was
//                                    left out. g = 0: the half-vector bins of the Integral-
//                                    Radiance tables (DirectionGrid{radiance_dirs, 0}); g = 1: the
//                                    parallax view directions (DirectionGrid{parallax_dirs,
//                                    min_cos}). An absent instance means every bin is covered.
//   ScenePlan instance 0: u8 {1, 64} one ScenePlanRecord: what else was left out, the scene's hash
//
// The planned tables are flagged in their own info records: the compressed parallax
// (kEntropyPlannedFlag, parallax_sections.hpp: the directions of bin map 1 only) and the compressed
// Integral-Radiance tables (kCompressedPlannedFlag, compressed_layout.hpp: the bins of bin map 0
// only, zero basis columns elsewhere). Queries of what was left out answer OutOfPlan, never a
// number.
//
// C++17, standard library only, noexcept, no allocation; safe on untrusted assets.
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/asset.hpp"

namespace clothbake::reader {

inline constexpr uint32_t kHalfVectorBinMap = 0;  // BinMap instance of the radiance tables' bins
inline constexpr uint32_t kViewBinMap = 1;        // BinMap instance of the parallax directions

// ScenePlanRecord.flags
inline constexpr uint32_t kPlanNoTransmission = 1u;  // no light behind the cloth: queries with the
                                                     // light and the viewer on opposite sides
                                                     // (transmission, delta) are not answered
inline constexpr uint32_t kPlanKnownFlags = kPlanNoTransmission;

struct ScenePlanRecord {
  uint32_t flags;                  // kPlan* bits; unknown bits: CBK-E015
  uint32_t half_vector_bins_kept;  // covered bins of bin map 0 (all bins when it is absent)
  uint32_t view_bins_kept;         // covered bins of bin map 1 (likewise)
  uint32_t reserved0;              // zero
  uint64_t scene_hash;             // XXH64 of the scene file's bytes (information)
  double max_error;                // the scene's error budget [render] max_error, (0, 1]
  unsigned char reserved[32];      // zero
};
static_assert(sizeof(ScenePlanRecord) == 64);
static_assert(alignof(ScenePlanRecord) == 8);
static_assert(offsetof(ScenePlanRecord, flags) == 0);
static_assert(offsetof(ScenePlanRecord, half_vector_bins_kept) == 4);
static_assert(offsetof(ScenePlanRecord, view_bins_kept) == 8);
static_assert(offsetof(ScenePlanRecord, reserved0) == 12);
static_assert(offsetof(ScenePlanRecord, scene_hash) == 16);
static_assert(offsetof(ScenePlanRecord, max_error) == 24);
static_assert(offsetof(ScenePlanRecord, reserved) == 32);

// One direction grid's bin map.
struct BinMapView {
  uint32_t bins_per_side = 0;     // n (0: the asset has no map for this grid: every bin covered)
  const uint8_t* mask = nullptr;  // n * n entries, 0 or 1, in the asset's bytes
  uint32_t kept = 0;              // entries equal to 1

  bool present() const noexcept { return mask != nullptr; }
  // Whether `bin` (< n^2) is covered; every bin is when there is no map.
  bool covers(uint32_t bin) const noexcept { return mask == nullptr || mask[bin] != 0; }
};

// Reads bin map `instance`. Absent: *out is the empty map (present() false) and the status is Ok.
// Errors: Unsupported (payload version other than 1), WrongType (CBK-E015: not u8 {n, n}, n of
// 1..256, or n different from `expected_bins_per_side` when that is not 0), Malformed (CBK-E021:
// an entry other than 0 or 1, or no bin covered).
Status read_bin_map(const Asset& asset, uint32_t instance, uint32_t expected_bins_per_side,
                    BinMapView* out) noexcept;

// Reads the ScenePlanRecord. Absent: *present = false, *out zeroed, Ok. Errors: Unsupported
// (version), WrongType (not u8 {1, 64}), Malformed (CBK-E015: unknown flag bits; CBK-E021:
// max_error outside (0, 1] or non-zero reserved bytes).
Status read_scene_plan(const Asset& asset, ScenePlanRecord* out, bool* present) noexcept;

}  // namespace clothbake::reader

// Parallax tables of an asset (paper Sec. 3.2, Eq. 2) and their summed-area tables for the parallax
// transition (Sec. 5.2): reader-side layout and queries (docs/raycast.md has the derivations).
//
// Definition. The reference plane is z_ref = the largest height of the tile. For texel (x, y) and
// view direction o (unit, towards the viewer, o.z >= min_cos) a ray enters at the texel centre on
// the reference plane and travels along -o; r(x, y, o) = z_hit - z_ref <= 0 (tile-side units) is
// the height of its first hit relative to the plane, so that Eq. 2 holds as printed:
//   u_new = u + (r / o.z) (o.x, o.y)      (u in tile units, [0, 1) over one tile)
// is the first visible point (model/parallax.hpp applies it).
//
// Two forms, each payload version 1:
//
// Raw (written by uncompressed bakes and with --keep-raw):
//   ParallaxTable instance 0: u8 {1, 64}   one ParallaxInfoRecord
//   ParallaxTable instance 1: u16 {D, N, N} depth codes: r = -code * depth_scale, D = n^2 view
//                                          directions (bin (i, j) of DirectionGrid{n, min_cos} at
//                                          index j * n + i), texel (x, y) at [d][y][x]
//   ParallaxSat   instance 0: u32 {D, N, N} inclusive SATs of the codes, modulo 2^32:
//                                          sat[d][y][x] = sum of code[d][y'][x'], y' <= y, x' <= x
// With 16-bit codes a sum over any rectangle of at most 65537 texels is below 2^32, so modular
// differences of four SAT values are exact; larger rectangles are summed in bands (exact too).
//
// Compressed (what a bake writes; parallax_hierarchy.hpp, compress/parallax_hierarchy.hpp writes
// it, docs/compression.md "Hierarchical parallax" says why): 16-bit codes with per-direction
// steps from the bake's error target, each direction's block predicted from up to four others
// and entropy-coded with the block coder (parallax_entropy.hpp):
//   ParallaxEntropy instance 0: u8 {1, 64}        one CompressedParallaxInfoRecord (bits 16)
//   ParallaxEntropy instance 1: f64 {D}           step[d]: r = -code * step[d]
//   ParallaxEntropy instance 2: u64 {D + 1}       block offsets into instance 3 (0, ..., its size)
//   ParallaxEntropy instance 3: u8 {bytes}        the D blocks
//   ParallaxEntropy instance 4: u16 {G, 23, 256}  frequency tables of G block groups
//   ParallaxEntropy instance 5: u32 {D}           prediction weights m[d] in [1, 2^24]
// No SAT is stored: the view decodes a direction's plane (N^2 u16, after the planes it
// references, at most two levels, which stay decoded too) and builds its u32 SAT the first time
// a query needs that direction (thread-safe, once per direction), so that opening costs a check
// of the offsets only. A scene-planned table (info flags kEntropyPlannedFlag) stores only the
// directions of bin map 1 (the others are empty blocks); a query whose bilinear bins (weight > 0)
// include a direction that was left out answers OutOfPlan, never a number; covers() tells
// beforehand.
//
// Queries take the view direction as any finite non-zero vector; it is normalised and, below the
// cap, moved onto the cap's rim at the same azimuth (straight down: +x azimuth), and that
// direction is used both for the table lookup (bilinear between the 4 nearest bin centres,
// model::DirectionGrid::bilinear_fast: the concentric map without atan2, equal to bilinear within
// n * 1e-8 in the weights; the evaluator and the scene plans use the same lookup) and in Eq. 2,
// so offsets stay bounded by range * tan(theta_cut).
//
// C++17, standard library only, noexcept; safe on untrusted assets that Asset::open accepted
// (shapes, parameter ranges and block offsets are checked by ParallaxView::open; a block that does
// not decode reads as zero codes, and decode_all reports it). Allocation: the raw form none (it
// views the asset); the compressed form, with new (std::nothrow), its block directory at open and
// each direction's decoded plane and SAT on first use (decoded_bytes() counts them); a failed
// allocation is reported (Unsupported), never thrown.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>

#include "formats/reader/asset.hpp"
#include "formats/reader/radiance_query.hpp"  // Footprint, plan_footprint

namespace clothbake::reader {

inline constexpr uint32_t kParallaxInfoInstance = 0;
inline constexpr uint32_t kParallaxCodesInstance = 1;
inline constexpr uint32_t kMaxParallaxDirs = 256;
inline constexpr uint32_t kMaxParallaxResolution = 16384;

// Info v1: one record, shape {1, 64}.
struct ParallaxInfoRecord {
  uint32_t resolution;            // N
  uint32_t dirs;                  // n: n x n view directions
  double min_cos;                 // the cap, [0, 1)
  double reference_height;        // z_ref, tile-side units (finite)
  double depth_scale;             // tile-side units per code, finite, >= 0 (0: flat map)
  double max_quantization_error;  // max |r - decoded r| over the table (<= depth_scale / 2)
  double max_offset;              // max |Eq. 2 offset| over the table's bin centres, tile units
  unsigned char reserved[16];     // zero
};
static_assert(sizeof(ParallaxInfoRecord) == 64);
static_assert(alignof(ParallaxInfoRecord) == 8);
static_assert(offsetof(ParallaxInfoRecord, resolution) == 0);
static_assert(offsetof(ParallaxInfoRecord, dirs) == 4);
static_assert(offsetof(ParallaxInfoRecord, min_cos) == 8);
static_assert(offsetof(ParallaxInfoRecord, reference_height) == 16);
static_assert(offsetof(ParallaxInfoRecord, depth_scale) == 24);
static_assert(offsetof(ParallaxInfoRecord, max_quantization_error) == 32);
static_assert(offsetof(ParallaxInfoRecord, max_offset) == 40);
static_assert(offsetof(ParallaxInfoRecord, reserved) == 48);

// Compressed info (ParallaxEntropy instance 0): one record, shape {1, 64}.
struct CompressedParallaxInfoRecord {
  uint32_t resolution;      // N, 1..16384
  uint32_t dirs;            // n: n x n view directions, 1..256
  uint32_t bits;            // bits per code: 16
  uint32_t flags;           // 0, or kEntropyPlannedFlag (parallax_entropy.hpp)
  double min_cos;           // the cap, [0, 1)
  double reference_height;  // z_ref, tile-side units (finite)
  double max_offset;        // max |Eq. 2 offset| of the raw table's bin centres, tile units
  double rms_offset_error;  // bake-time RMS |Eq. 2 offset error| over texels x bins, texels
  double max_offset_error;  // bake-time max of the same, texels
  double max_depth_error;   // bake-time max |r - decoded r|, tile-side units
};
static_assert(sizeof(CompressedParallaxInfoRecord) == 64);
static_assert(alignof(CompressedParallaxInfoRecord) == 8);
static_assert(offsetof(CompressedParallaxInfoRecord, resolution) == 0);
static_assert(offsetof(CompressedParallaxInfoRecord, dirs) == 4);
static_assert(offsetof(CompressedParallaxInfoRecord, bits) == 8);
static_assert(offsetof(CompressedParallaxInfoRecord, flags) == 12);
static_assert(offsetof(CompressedParallaxInfoRecord, min_cos) == 16);
static_assert(offsetof(CompressedParallaxInfoRecord, reference_height) == 24);
static_assert(offsetof(CompressedParallaxInfoRecord, max_offset) == 32);
static_assert(offsetof(CompressedParallaxInfoRecord, rms_offset_error) == 40);
static_assert(offsetof(CompressedParallaxInfoRecord, max_offset_error) == 48);
static_assert(offsetof(CompressedParallaxInfoRecord, max_depth_error) == 56);

// Which form ParallaxView::open uses.
enum class ParallaxSource {
  Auto,        // the raw table when the asset has one (exact), the compressed one otherwise
  Raw,         // the raw table only
  Compressed,  // the compressed table only
};

// The answer of a query.
struct ParallaxSample {
  double r = 0;               // ray depth (<= 0), tile-side units; the footprint mean for areas
  double offset[2] = {0, 0};  // Eq. 2: (r / o.z) (o.x, o.y), tile units (times N for texels)
  double direction[3] = {0, 0, 1};  // o as used: normalised, clamped into the cap
};

// The same queries on the raw and on the compressed form. The view points into the Asset's bytes
// (it must outlive the view); the compressed form's decoded planes and prefix sums are owned
// (shared between copies). Every const member is thread-safe.
class ParallaxView {
 public:
  // Errors: NotFound (CBK-E019: no parallax table of the form asked for, or a planned table
  // without bin_map instance 1), WrongType/Unsupported (CBK-E015: version, element type, shape,
  // SAT shape differing from the table's, bits, flags; CBK-E024 beyond 4 GiB of decoded planes),
  // Malformed (CBK-E021: a parameter, step, weight, table or block offset out of range, NaN/Inf
  // included). The raw SAT is optional (has_sat()); the compressed form always answers
  // footprints (SATs built on demand; footprint_depth returns Unsupported if one cannot be
  // allocated).
  Status open(const Asset& asset, ParallaxSource source = ParallaxSource::Auto) noexcept;
  bool is_open() const noexcept { return codes_ != nullptr || static_cast<bool>(packed_); }
  bool has_sat() const noexcept { return sat_ != nullptr || static_cast<bool>(packed_); }
  bool is_compressed() const noexcept { return static_cast<bool>(packed_); }
  // A scene-planned table: only the directions of its bin map are stored.
  bool is_planned() const noexcept { return covered_ != nullptr; }
  // Whether direction bin `bin` (< dirs^2) is stored (always, except in a planned table).
  bool covers(uint32_t bin) const noexcept { return covered_ == nullptr || covered_[bin] != 0; }
#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
  // Stored view directions (dirs^2, or the bin map's count in a planned table).
  uint32_t stored_dirs() const noexcept;
#endif
  // Compressed form: its record (zero for the raw form).
  const CompressedParallaxInfoRecord& compressed_info() const noexcept {
    return packed_info_;
  }
#ifndef CLOTHBAKE_SINGLE_FILE  // reports of the tools, not used by shading
  // Bytes of the SATs and decoded planes the compressed form has built so far (0 for raw).
  uint64_t decoded_bytes() const noexcept;
  // Compressed form: decodes the block of `bin` now (no-op for raw); false if it cannot be
  // allocated or the direction is not stored. A block that does not decode exactly reads as zero
  // codes (validate reports it: decode_all). Thread-safe. Precondition: bin < dirs^2.
  bool ensure_plane(uint32_t bin) const noexcept;
#endif
  // Compressed form: decodes every stored block and reports the first that does not decode
  // exactly (CBK-E021) or cannot be allocated (Unsupported). OK for raw.
  Status decode_all() const noexcept;
  // The depth step of `bin` (tile-side units per code; the raw form's depth_scale for every bin).
  double depth_step(uint32_t bin) const noexcept;
  // The N^2 codes of `bin`, row-major (texel index t = y N + x; r = -code * depth_step(bin)): the
  // raw table's plane in the asset, or the compressed form's decoded plane (decoded now if it is
  // not yet; owned by the view). Null when the bin is not stored (planned) or its plane cannot be
  // allocated: bin_depth then answers 0. For callers that read many texels of one bin (the
  // evaluator's samples) without a branch per texel. Thread-safe. Precondition: bin < dirs^2.
  const uint16_t* bin_codes(uint32_t bin) const noexcept;

  const ParallaxInfoRecord& info() const noexcept {
    return info_;
  }
  uint32_t resolution() const noexcept {
    return info_.resolution;
  }
  uint32_t dirs() const noexcept {
    return info_.dirs;
  }

  // The stored code of one bin at texel (x, y) (any integers: the tile wraps); the compressed
  // form decodes the bin's block first. Precondition: bin < dirs^2 and covers(bin).
  uint32_t bin_code(uint32_t bin, int64_t x, int64_t y) const noexcept;
  // r of one bin at texel (x, y) (any integers: the tile wraps). Precondition: bin < dirs^2 and
  // covers(bin) (an uncovered bin gives 0).
  double bin_depth(uint32_t bin, int64_t x, int64_t y) const noexcept;
  // The same for texel index t = y N + x (t < N^2, no wrapping): the evaluator's hot path.
  double bin_depth_at(uint32_t bin, uint64_t t) const noexcept {
    return covers(bin) ? -double(code(bin, t)) * depth_step(bin) : 0.0;
  }
  // sum over k < 4 with weight[k] > 0 of weight[k] * bin_depth(bin[k], x, y), wrapping (x, y)
  // once: the per-texel depth for bilinear weights computed once per view (the evaluator's hot
  // path). Precondition: every bin with a positive weight < dirs^2.
  double weighted_depth(const int bin[4], const double weight[4], int64_t x,
                        int64_t y) const noexcept;

  // The view direction a query uses for `view` (any finite non-zero vector): normalised and, below
  // the cap, moved onto the cap's rim at the same azimuth. InvalidArgument otherwise.
  Status view_direction(const double view[3], double o[3]) const noexcept;

  // r at texel (x, y) for view direction `view` (bilinear between bins), with its Eq. 2 offset.
  // InvalidArgument for a zero or non-finite view; OutOfPlan when a bin of the lookup (weight > 0)
  // is not covered (a planned table).
  Status depth(int64_t x, int64_t y, const double view[3], ParallaxSample* out) const noexcept;

  // The mean of r over a footprint rectangle (texel units, any size and position; the tile wraps;
  // partially covered texels count with their covered area), from the SATs in O(1) for N <= 256
  // (4 to 9 lookups per bin, at most 4 bins), and the Eq. 2 offset of that mean. A zero-area
  // rectangle gives the texel that contains (x0, y0). Errors: NotFound (no SAT), InvalidArgument
  // (rectangle as for plan_footprint, view).
  Status footprint_depth(const Footprint& rect, const double view[3],
                         ParallaxSample* out) const noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
  // The exact sum of the codes of `bin` over texels [0, x) x [0, y), 0 <= x, y <= N (from the
  // SAT; exact for any N). Precondition: has_sat(), bin < dirs^2; compressed form: the bin's SAT
  // built (footprint_depth or ensure_sat did), else 0.
  uint64_t code_prefix_sum(uint32_t bin, uint32_t x, uint32_t y) const noexcept;
#endif
  // Builds the compressed form's SAT of `bin` now (no-op for raw); false if it cannot be allocated
  // or the direction is not stored. Thread-safe. Precondition: bin < dirs^2.
  bool ensure_sat(uint32_t bin) const noexcept;

 private:
  double footprint_code_sum(uint32_t bin, const FootprintPlan& plan) const noexcept;
  double prefix_integral(uint32_t bin, const uint32_t* table, double x, double y) const noexcept;
  uint64_t prefix_sum_of(const uint32_t* table, uint32_t x, uint32_t y) const noexcept;
  const uint32_t* bin_sat(uint32_t bin) const noexcept;
  Status out_of_plan(int bin) const noexcept;
  // Code of texel index t (y * N + x) in direction bin (covered); 0 when a compressed block is
  // unavailable.
  uint32_t code(uint32_t bin, uint64_t t) const noexcept {
    const uint64_t plane_size = uint64_t(info_.resolution) * info_.resolution;
    if (codes_) return uint32_t(codes_[uint64_t(bin) * plane_size + t]);
    const uint16_t* p = plane16(bin);
    return p ? uint32_t(p[t]) : 0u;
  }
  const uint16_t* plane16(uint32_t bin) const noexcept;  // compressed form: the decoded plane

  struct Packed;  // the compressed form's decoded planes and on-demand SATs
  // A counted reference to the Packed that the copies of a view share, created without a
  // throwing allocation (a std::shared_ptr's control block may throw, and the reader is built
  // without exceptions). Copies and the last release are thread-safe (atomic count).
  class SharedPacked {
   public:
    SharedPacked() noexcept = default;
    explicit SharedPacked(Packed* adopted) noexcept : p_(adopted) {}  // a new Packed's reference
    SharedPacked(const SharedPacked& other) noexcept;
    SharedPacked(SharedPacked&& other) noexcept : p_(other.p_) { other.p_ = nullptr; }
    SharedPacked& operator=(SharedPacked other) noexcept {
      Packed* held = p_;
      p_ = other.p_;
      other.p_ = held;
      return *this;
    }
    ~SharedPacked();
    Packed* operator->() const noexcept { return p_; }
    Packed& operator*() const noexcept { return *p_; }
    explicit operator bool() const noexcept { return p_ != nullptr; }

   private:
    Packed* p_ = nullptr;
  };
  Status open_raw(const Asset& asset) noexcept;
  Status open_coded(const Asset& asset) noexcept;

  ParallaxInfoRecord info_{};
  const uint16_t* codes_ = nullptr;  // raw form
  const uint32_t* sat_ = nullptr;    // raw form (optional)
  const double* steps_ = nullptr;    // compressed form: D values in the asset
  const uint8_t* stream_ = nullptr;  // compressed form: the blocks
  const uint64_t* offsets_ = nullptr;
  const uint16_t* tables_ = nullptr;   // compressed form: groups_ x 23 x 256
  const uint32_t* weights_ = nullptr;  // compressed form: m[d]
  uint32_t groups_ = 0;
  CompressedParallaxInfoRecord packed_info_{};
  SharedPacked packed_;
  const uint8_t* covered_ = nullptr;  // planned table: bin_map instance 1 (1 = stored)
  bool exact_sums_ = false;  // 65535 N^2 < 2^32: every prefix sum is one exact u32 (N <= 256)
};

}  // namespace clothbake::reader

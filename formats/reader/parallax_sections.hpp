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
// Sections (all version 1), raw form (format 1.0):
//   ParallaxTable instance 0: u8 {1, 64}   one ParallaxInfoRecord
//   ParallaxTable instance 1: u16 {D, N, N} depth codes: r = -code * depth_scale, D = n^2 view
//                                          directions (bin (i, j) of DirectionGrid{n, min_cos} at
//                                          index j * n + i), texel (x, y) at [d][y][x]
//   ParallaxSat   instance 0: u32 {D, N, N} inclusive SATs of the codes, modulo 2^32:
//                                          sat[d][y][x] = sum of code[d][y'][x'], y' <= y, x' <= x
// With 16-bit codes a sum over any rectangle of at most 65537 texels is below 2^32, so modular
// differences of four SAT values are exact; larger rectangles are summed in bands (exact too).
//
// Compressed form (format 1.1; compress/parallax_pca.hpp writes it, docs/compression.md says why):
//   ParallaxCompressed instance 0: u8 {1, 64}    one CompressedParallaxInfoRecord
//   ParallaxCompressed instance 1: f32 {K+1, D}  B: row 0 the mean, rows 1..K the scaled basis
//   ParallaxCompressed instance 2: i16 {N, N, K} q: texel (x, y)'s K coefficients at [y][x][.]
//   r(x, y, d) = B[0][d] + sum_{k=1..K} q[y][x][k-1] B[k][d]   (double accumulation)
// open() builds the exact integer prefix sums of the K coefficients ((N+1)^2 K int64, interleaved
// per SAT point): a footprint mean is then B[0] + sum_k (integral of q_k / area) B[k], the same
// linear form as a texel, in O(K) whatever the footprint size. Unlike raw codes, decoded r can
// be slightly above 0 (within the stored error); nothing clamps it, so that footprint means stay
// the exact means of the per-texel values.
//
// Queries take the view direction as any finite non-zero vector; it is normalised and, below the
// cap, moved onto the cap's rim at the same azimuth (straight down: +x azimuth), and that
// direction is used both for the table lookup (bilinear between the 4 nearest bin centres) and in
// Eq. 2, so offsets stay bounded by range * tan(theta_cut).
//
// C++17, standard library only, noexcept, no allocation; safe on untrusted assets that
// Asset::open accepted (shapes and parameter ranges are checked by ParallaxView::open).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "formats/reader/asset.hpp"
#include "formats/reader/radiance_query.hpp"  // Footprint, plan_footprint

namespace clothbake::reader {

inline constexpr uint32_t kParallaxInfoInstance = 0;
inline constexpr uint32_t kParallaxCodesInstance = 1;
inline constexpr uint32_t kMaxParallaxDirs = 256;
inline constexpr uint32_t kMaxParallaxResolution = 16384;
inline constexpr uint32_t kCompressedParallaxInfoInstance = 0;
inline constexpr uint32_t kCompressedParallaxBasisInstance = 1;
inline constexpr uint32_t kCompressedParallaxCoeffsInstance = 2;
inline constexpr uint32_t kMaxParallaxRank = 255;
// Largest decoded prefix-sum table open() allocates for a compressed table (bytes).
inline constexpr uint64_t kMaxParallaxDecodedBytes = uint64_t(4) << 30;

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

// Compressed info v1: one record, shape {1, 64}.
struct CompressedParallaxInfoRecord {
  uint32_t resolution;      // N, 1..16384
  uint32_t dirs;            // n: n x n view directions, 1..256
  uint32_t rank;            // K, 0..255
  uint32_t flags;           // 0 in version 1
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
static_assert(offsetof(CompressedParallaxInfoRecord, rank) == 8);
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
// (it must outlive the view); the compressed form's prefix sums are owned (shared between copies).
class ParallaxView {
 public:
  // Errors: NotFound (CBK-E019: no parallax table of the form asked for), WrongType/Unsupported
  // (CBK-E015: version, element type, shape, SAT shape differing from the table's, flags),
  // Malformed (CBK-E021: a parameter out of range; CBK-E017: a NaN/Inf basis value), Unsupported
  // (the compressed table's prefix sums would exceed kMaxParallaxDecodedBytes or cannot be
  // allocated). The raw SAT is optional (has_sat()); the compressed form always has footprints.
  Status open(const Asset& asset, ParallaxSource source = ParallaxSource::Auto) noexcept;
  bool is_open() const noexcept { return codes_ != nullptr || packed_ != nullptr; }
  bool has_sat() const noexcept { return sat_ != nullptr || packed_ != nullptr; }
  bool is_compressed() const noexcept { return packed_ != nullptr; }
  // Compressed form: its record and rank K (0 for the raw form).
  const CompressedParallaxInfoRecord& compressed_info() const noexcept { return packed_info_; }
  uint32_t rank() const noexcept { return packed_info_.rank; }
  // Bytes of the decoded prefix sums and basis held by the compressed form (0 for raw).
  uint64_t decoded_bytes() const noexcept;

  const ParallaxInfoRecord& info() const noexcept { return info_; }
  uint32_t resolution() const noexcept { return info_.resolution; }
  uint32_t dirs() const noexcept { return info_.dirs; }

  // r of one bin at texel (x, y) (any integers: the tile wraps). Precondition: bin < dirs^2.
  // Compressed form: O(K).
  double bin_depth(uint32_t bin, int64_t x, int64_t y) const noexcept;
  // sum over k < 4 with weight[k] > 0 of weight[k] * bin_depth(bin[k], x, y), wrapping (x, y)
  // once: the per-texel depth for bilinear weights computed once per view (the evaluator's hot
  // path). Precondition: every bin with a positive weight < dirs^2. Compressed form: O(4 K).
  double weighted_depth(const int bin[4], const double weight[4], int64_t x,
                        int64_t y) const noexcept;

  // The view direction a query uses for `view` (any finite non-zero vector): normalised and, below
  // the cap, moved onto the cap's rim at the same azimuth. InvalidArgument otherwise.
  Status view_direction(const double view[3], double o[3]) const noexcept;

  // r at texel (x, y) for view direction `view` (bilinear between bins), with its Eq. 2 offset.
  // InvalidArgument for a zero or non-finite view.
  Status depth(int64_t x, int64_t y, const double view[3], ParallaxSample* out) const noexcept;

  // The mean of r over a footprint rectangle (texel units, any size and position; the tile wraps;
  // partially covered texels count with their covered area), from the SATs in O(1) for N <= 256
  // (4 to 9 lookups per bin, at most 4 bins; compressed: 4 to 9 prefix points of K coefficients
  // each, whatever N), and the Eq. 2 offset of that mean. A zero-area
  // rectangle gives the texel that contains (x0, y0). Errors: NotFound (no SAT), InvalidArgument
  // (rectangle as for plan_footprint, view).
  Status footprint_depth(const Footprint& rect, const double view[3],
                         ParallaxSample* out) const noexcept;

  // The exact sum of the codes of `bin` over texels [0, x) x [0, y), 0 <= x, y <= N (from the
  // SAT; exact for any N). Precondition: the raw form with a SAT (!is_compressed()), bin < dirs^2.
  uint64_t code_prefix_sum(uint32_t bin, uint32_t x, uint32_t y) const noexcept;

 private:
  double footprint_code_sum(uint32_t bin, const FootprintPlan& plan) const noexcept;
  double prefix_integral(uint32_t bin, double x, double y) const noexcept;

  struct Packed;  // the compressed form's decoded tables
  Status open_raw(const Asset& asset) noexcept;
  Status open_compressed(const Asset& asset) noexcept;
  double packed_footprint(const FootprintPlan& plan, const int bin[4], const double weight[4],
                          double area) const noexcept;

  ParallaxInfoRecord info_{};
  const uint16_t* codes_ = nullptr;
  const uint32_t* sat_ = nullptr;
  CompressedParallaxInfoRecord packed_info_{};
  std::shared_ptr<const Packed> packed_;
};

}  // namespace clothbake::reader

// Per-texel ASG visibility of an asset (paper Sec. 3.1, 4.2; docs/raycast.md): the lobe of every
// texel and the RMS error of its fit, reader side.
//
// V(x, w) ~ G(w) = c [w.z_axis > 0] exp(-lambda (w.x_axis)^2 - mu (w.y_axis)^2) (model/asg.hpp),
// fitted to binary visibility sampled over the upper hemisphere of light directions (the macro
// surface's, z > 0) from the texel's surface point.
//
// Sections (all version 1):
//   VisibilityAsg instance 0: u8 {1, 64}    one VisibilityInfoRecord
//   VisibilityAsg instance 1: u16 {N, N, 6} model::AsgRecord of texel (x, y) at [y][x]: axis_u,
//                                           axis_v, rotation, lambda, mu, amplitude (encodings in
//                                           model/asg.hpp)
//   AsgFitError   instance 0: f32 {N, N}    RMS of (G - V) over the sampled directions, of the
//                                           stored (quantised) lobe, in [0, 2]; optional
//
// C++17, standard library only, noexcept, no allocation; safe on untrusted assets that
// Asset::open accepted (any 12 bytes decode to a valid lobe).
#pragma once

#include <cstddef>
#include <cstdint>

#include "formats/reader/asset.hpp"
#include "model/asg.hpp"

namespace clothbake::reader {

inline constexpr uint32_t kVisibilityInfoInstance = 0;
inline constexpr uint32_t kVisibilityRecordsInstance = 1;
inline constexpr uint32_t kMaxVisibilityResolution = 16384;
inline constexpr uint32_t kAsgRecordFields = 6;

// Info v1: one record, shape {1, 64}.
struct VisibilityInfoRecord {
  uint32_t resolution;          // N
  uint32_t dirs;                // n: the fit used n x n directions of DirectionGrid{n, 0}
  double normal_offset_texels;  // ray origin offset along the height-field normal, texels
  double max_bandwidth;         // model::kAsgMaxBandwidth of the record encoding
  double max_amplitude;         // model::kAsgMaxAmplitude of the record encoding
  double mean_fit_error;        // mean of the fit errors
  double max_fit_error;         // their maximum
  unsigned char reserved[16];   // zero
};
static_assert(sizeof(VisibilityInfoRecord) == 64);
static_assert(alignof(VisibilityInfoRecord) == 8);
static_assert(offsetof(VisibilityInfoRecord, resolution) == 0);
static_assert(offsetof(VisibilityInfoRecord, dirs) == 4);
static_assert(offsetof(VisibilityInfoRecord, normal_offset_texels) == 8);
static_assert(offsetof(VisibilityInfoRecord, max_bandwidth) == 16);
static_assert(offsetof(VisibilityInfoRecord, max_amplitude) == 24);
static_assert(offsetof(VisibilityInfoRecord, mean_fit_error) == 32);
static_assert(offsetof(VisibilityInfoRecord, max_fit_error) == 40);
static_assert(offsetof(VisibilityInfoRecord, reserved) == 48);
static_assert(sizeof(model::AsgRecord) == kAsgRecordFields * sizeof(uint16_t));

class VisibilityAsgView {
 public:
  // Errors: NotFound (CBK-E019), WrongType/Unsupported (CBK-E015: version, element type, shape;
  // a record encoding other than this reader's model/asg.hpp), Malformed (CBK-E021: a parameter
  // or fit error out of range). The fit error section is optional (has_fit_error()).
  Status open(const Asset& asset) noexcept;
  bool is_open() const noexcept { return records_ != nullptr; }
  bool has_fit_error() const noexcept { return fit_error_ != nullptr; }

  const VisibilityInfoRecord& info() const noexcept { return info_; }
  uint32_t resolution() const noexcept { return info_.resolution; }

  // The stored record and its decoded lobe at texel (x, y) (any integers: the tile wraps).
  model::AsgRecord record(int64_t x, int64_t y) const noexcept;
  model::AsgParams<double> lobe(int64_t x, int64_t y) const noexcept;
  // The same at texel index t = y N + x (t < N^2: not checked; no division, for per-sample use).
  model::AsgRecord record_at(uint64_t t) const noexcept;
  model::AsgParams<double> lobe_at(uint64_t t) const noexcept;
  // Where record_at(t) reads (for a caller's prefetch); t < N^2, not checked.
  const void* record_address(uint64_t t) const noexcept { return records_ + t * kAsgRecordFields; }
  // RMS fit error at (x, y); NaN without the fit error section.
  double fit_error(int64_t x, int64_t y) const noexcept;

  // V(x, w) from the ASG for a light direction w (any finite non-zero vector, normalised here),
  // clamped to [0, 1] (a least-squares lobe may exceed 1 near its axis). The visibility was
  // sampled over w.z > 0 only; below the macro horizon this returns the lobe's own value, which
  // is 0 unless its axis is tilted. InvalidArgument for a zero or non-finite w.
  Status visibility(int64_t x, int64_t y, const double w[3], double* out) const noexcept;

 private:
  VisibilityInfoRecord info_{};
  const uint16_t* records_ = nullptr;
  const float* fit_error_ = nullptr;
};

}  // namespace clothbake::reader

// The compressed parallax table of format 1.1 (paper Sec. 3.2, Eq. 2; layout:
// formats/reader/parallax_sections.hpp; docs/compression.md, "Compressed parallax", has the
// measurements that chose this form over a directional PCA and over zstd-coded codes).
//
// Form. The raw table stores r = -code * depth_scale with one 16-bit step for the whole table,
// i.e. 1/65535 of the tile's height range (~0.001 texel at 256^2): twenty times finer than a
// renderer can see. The compressed form requantises every direction d to 8 bits with its own step
//   step[d] = depth_scale * top[d] / 255,   top[d] = the largest raw code of direction d,
//   code8 = round(code / (top[d] / 255)),   r = -code8 * step[d]
// (top[d] = 0: step 0 and every code 0, so a flat direction, or a flat map, decodes to exactly 0).
// Half the step is the largest depth error; the Eq. 2 offset error is that times N tan(theta_d).
// 1 byte per texel and direction, no SAT stored: the reader builds a direction's SAT when a
// footprint query first needs it. When the 8-bit codes miss the target error (tall weaves whose
// offsets reach ~100 texels), the form falls back to 16 bits: the raw codes themselves, with
// step[d] = depth_scale, still without a stored SAT (a third of the raw form's bytes).
//
// Deterministic (no threads, no floating-point reductions that depend on order beyond the fixed
// loops). C++20. Errors: clothbake::Error(Input) for an empty table.
#pragma once

#include <cstdint>
#include <vector>

#include "formats/reader/parallax_sections.hpp"  // CompressedParallaxInfoRecord

namespace clothbake::formats {
struct Section;
}

namespace clothbake::compress {

// Default [bake] parallax_max_error: RMS Eq. 2 offset error in texels over every texel and bin
// centre; 8-bit codes above it give way to 16-bit ones (docs/compression.md).
inline constexpr double kDefaultParallaxMaxError = 0.05;

// The raw table as the parallax stage produces it (raycast::ParallaxTable without the dependency).
struct ParallaxCodes {
  const uint16_t* codes = nullptr;  // [dir][y][x], dir = j * n + i
  int resolution = 0;               // N
  int dirs = 0;                     // n
  double min_cos = 0.6;
  double depth_scale = 0.0;  // r = -code * depth_scale
  double reference_height = 0.0;
  double max_offset = 0.0;  // tile units (information)
};

struct QuantisedParallax {
  int resolution = 0, dirs = 0;
  double min_cos = 0.6, reference_height = 0.0, max_offset = 0.0;
  int bits = 8;                        // 8 or 16
  std::vector<double> steps;           // D
  std::vector<uint8_t> codes;          // D x N x N when bits == 8
  std::vector<uint16_t> codes16;       // D x N x N when bits == 16
  double rms_offset_error_8bit = 0.0;  // what the 8-bit codes measured (also when rejected)
  // Against the raw codes, at the bin centres.
  double rms_offset_error = 0.0;     // texels
  double max_offset_error = 0.0;     // texels
  double share_above_quarter = 0.0;  // share of (texel, bin) entries with offset error > 0.25
  double max_depth_error = 0.0;      // tile-side units
  double seconds = 0.0;              // wall time of quantise_parallax

  uint64_t payload_bytes() const {
    return 64 + steps.size() * 8 + codes.size() + codes16.size() * 2;
  }
};

// N tan(theta_d) at the bin centres: texels of Eq. 2 offset per unit of depth, D values.
std::vector<double> parallax_offset_per_depth(int resolution, int dirs, double min_cos);

// Throws Error(Input) for an empty table or max_error outside (0, 1] (naming
// bake.parallax_max_error): the check of every parallax compressor.
void check_parallax_compression_input(const ParallaxCodes& raw, double max_error);

// The info record of a compressed form (QuantisedParallax, HierarchicalParallax): its shape and
// measured errors, with the given bits and flags.
template <class Form>
reader::CompressedParallaxInfoRecord parallax_info_record(const Form& p, uint32_t bits,
                                                          uint32_t flags) {
  reader::CompressedParallaxInfoRecord info{};
  info.resolution = uint32_t(p.resolution);
  info.dirs = uint32_t(p.dirs);
  info.bits = bits;
  info.flags = flags;
  info.min_cos = p.min_cos;
  info.reference_height = p.reference_height;
  info.max_offset = p.max_offset;
  info.rms_offset_error = p.rms_offset_error;
  info.max_offset_error = p.max_offset_error;
  info.max_depth_error = p.max_depth_error;
  return info;
}

// Requantises the raw codes to 8 bits and measures the errors; if their RMS offset error is above
// max_error (texels), returns the 16-bit form (the raw codes, errors 0) instead. Throws
// Error(Input) for an empty table or max_error outside (0, 1] naming bake.parallax_max_error.
QuantisedParallax quantise_parallax(const ParallaxCodes& raw,
                                    double max_error = kDefaultParallaxMaxError);

// ParallaxCompressed instances 0 (info), 1 (steps), 2 (codes).
std::vector<formats::Section> compressed_parallax_sections(const QuantisedParallax& packed);

}  // namespace clothbake::compress

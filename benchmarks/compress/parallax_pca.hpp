// Principal components of the parallax table's per-texel directional vectors (paper Sec. 3.2,
// Eq. 2): the candidate form that docs/compression.md, "Compressed parallax", measured and did not
// choose (occlusion edges keep the RMS offset error near 1 texel at any affordable rank). Kept for
// benchmarks/compress/parallax_study (the measurement is reproducible); the asset's compressed
// form is compress/parallax_hierarchy.hpp.
//
// What is compressed. Per texel x the table holds D = n^2 depths r(x, d) <= 0 (one per view bin).
// r is smooth in the direction except at occlusion edges, so the D-vectors of all texels lie close
// to a low-dimensional subspace. The PCA runs in offset units: y(x, d) = w_d r(x, d) with
//   w_d = N max(tan(theta_d), kParallaxMinWeight)   (texels of Eq. 2 offset per unit of r)
// so that its squared residual is the squared Eq. 2 offset error in texels (directions within
// ~6 degrees of the zenith, whose offsets are tiny, are weighted as if at that angle). One basis
// for the whole tile (one C-PCA cell, compress/cpca.hpp with a single stratum and k = 1): a
// footprint query then needs the summed-area tables of the K coefficients only.
//
// Stored form (what the reader decodes, exactly):
//   r(x, d) = B[0][d] + sum_{k=1..K} q_k(x) B[k][d]      (tile-side units, double accumulation)
// B f32 {K + 1, D}: row 0 the mean, row k the k-th basis vector unweighted and multiplied by the
// coefficient step; q i16 {N, N, K}, |q| <= 32767 (step = max |c_k| / 32767 per component).
//
// Ranks: the smallest K (<= rank_cap) whose RMS offset error over all texels and bins, after
// quantisation, is at most max_error texels (chosen on the C-PCA's exact residuals, then
// checked on the stored form; if quantisation pushed it above, K grows by one until it holds or
// the cap is reached). A flat map (every code 0) gives K = 0 and B[0] = 0: every r is exactly 0.
//
// Deterministic for any thread count. C++20. Errors: clothbake::Error(Input) naming
// "bake.parallax_max_error" for a target outside (0, 1], shapes out of range.
#pragma once

#include <cstdint>
#include <vector>

#include "compress/parallax_codes.hpp"  // ParallaxCodes

namespace clothbake::compress {

inline constexpr double kDefaultParallaxPcaError = 0.05;  // texels
inline constexpr int kDefaultParallaxRankCap = 64;
inline constexpr int kMaxParallaxPcaRank = 255;
inline constexpr double kParallaxMinWeight = 0.1;  // floor of tan(theta) in the PCA weights

struct ParallaxPcaOptions {
  double max_error = kDefaultParallaxPcaError;  // texels, (0, 1]
  int rank_cap = kDefaultParallaxRankCap;       // 0..255
  int fixed_rank = -1;                          // >= 0: exactly this rank (studies, tests)
  int power_iterations = 2;
  uint64_t seed = 1;
};

struct ParallaxPca {
  int resolution = 0, dirs = 0, rank = 0;
  double min_cos = 0.6, reference_height = 0.0, max_offset = 0.0;
  std::vector<float> basis;           // (rank + 1) x D, row 0 the mean
  std::vector<int16_t> coefficients;  // N x N x rank, interleaved per texel
  // Measured on the stored form against the raw codes (bin centres).
  double rms_offset_error = 0.0;     // texels
  double max_offset_error = 0.0;     // texels
  double share_above_quarter = 0.0;  // share of (texel, bin) entries with offset error > 0.25
  double max_depth_error = 0.0;      // tile-side units
  double seconds = 0.0;              // wall time of compress_parallax

  uint64_t payload_bytes() const { return basis.size() * 4 + coefficients.size() * 2 + 64; }
};

// Per-bin weights w_d (texels per unit r) of the PCA, D values.
std::vector<double> parallax_offset_weights(int resolution, int dirs, double min_cos);

// Compresses the raw codes. Throws Error(Input) for options or shapes out of range.
ParallaxPca fit_parallax_pca(const ParallaxCodes& raw, const ParallaxPcaOptions& options);

// Measures the stored form against the raw codes (fills the four error fields of `packed`).
void measure_parallax_pca_error(const ParallaxCodes& raw, ParallaxPca* packed);

}  // namespace clothbake::compress

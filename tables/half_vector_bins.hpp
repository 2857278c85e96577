// Half-vector bins of the Integral-Radiance tables (paper Sec. 4.3) and the quadrature that makes
// each table entry a bin average (DESIGN.md, "Bins store bin averages").
//
// Bins: model::DirectionGrid{n, 0}, the equal-area concentric grid on the upper hemisphere
// (half vectors are folded, D(h) = D(-h)); bin (i, j) has index j * n + i and covers
// 2 pi / n^2 sr. Quadrature: s x s midpoints of the bin's square cell, equal weights 1 / s^2 (the
// map is equal-area, so equal square areas are equal solid angles): a stratified midpoint rule of
// the bin average. Directions are unit float vectors, bin-major.
//
// The 2-sigma rule (paper Sec. 4.3): a bin resolves a fibre-like SGGX lobe of roughness sigma
// (angular half-width ~ sigma) when its angular width, sqrt(2 pi / n^2) rad, is at most 2 sigma:
// n >= sqrt(2 pi) / (2 sigma). 32^2 bins (0.078 rad) resolve sigma >= 0.04, the paper's satin.
// Narrower lobes are still integrated exactly enough (bin averages, the quadrature adapts to
// sigma), but the bilinear reconstruction between bin centres blurs them: the bake warns and says
// which n would resolve them.
//
// C++20; safe for any argument values (clamped or rejected with clothbake::Error(Input)).
#pragma once

#include <string>
#include <vector>

namespace clothbake::tables {

inline constexpr int kMaxBinsPerSide = 256;
inline constexpr int kMaxSamplesPerBinSide = 16;

struct HalfVectorBins {
  int bins_per_side = 0;       // n
  int samples_per_side = 0;    // s
  std::vector<float> x, y, z;  // n^2 * s^2 unit directions; bin b's at [b s^2, (b + 1) s^2)
  int bin_count() const { return bins_per_side * bins_per_side; }
  int samples_per_bin() const { return samples_per_side * samples_per_side; }
};

// The quadrature directions. Errors (Input): n outside [1, 256], s outside [1, 16].
HalfVectorBins make_half_vector_bins(int bins_per_side, int samples_per_side);

// Angular width of one bin, sqrt(2 pi / n^2) radians.
double bin_angular_width(int bins_per_side);
// Smallest n whose bins resolve roughness sigma by the 2-sigma rule: ceil(sqrt(2 pi) / (2 sigma)).
int bins_per_side_for_roughness(double sigma);
// True when n x n bins resolve sigma (bin width <= 2 sigma, with a 1e-9 tolerance).
bool bins_resolve_roughness(int bins_per_side, double sigma);

// The default bins per side for a fabric whose narrowest roughness is sigma: bins at most sigma / 3
// wide, n = ceil(3 sqrt(2 pi) / sigma), clamped to [32, 128]. The 2-sigma rule above only keeps a
// lobe from vanishing between bin centres; the multi-scale control variate pairs the binned table
// value with the exact D at the same texel, and measured on the satin (sigma 0.06) the shipped
// estimator's whole-tile variance ratio against brute force (median over 16 light and view pairs)
// is 46 with 84^2 bins (sigma / 2) and 101 with 126^2 (sigma / 3; docs/evaluator.md, "The error
// budget"). The default twill (sigma 0.4) keeps 32^2.
int default_bins_per_side(double min_roughness);

// Quadrature points per bin side for the narrowest roughness sigma: the sub-cell spacing
// bin_width / s must not exceed sigma / 2 (4 points across the lobe's width), clamped to
// [2, 8]. 32^2 bins: sigma >= 0.079 -> 2, 0.06 -> 3, 0.04 -> 4, <= 0.02 -> 8 (docs/tables.md).
int default_samples_per_side(int bins_per_side, double min_roughness);

}  // namespace clothbake::tables

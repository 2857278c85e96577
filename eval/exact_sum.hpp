// The exact footprint average of Eq. 5 under the piecewise-constant texel model (the Reference
// method and the direct path of the multi-scale methods; docs/evaluator.md, "Reference").
//
// In view bin k, within one source texel q the parallax depth r_kq is constant, so
// x'_k(p) = p + delta_kq moves the part of q that P covers rigidly; that moved rectangle (at most
// one texel wide) overlaps at most 2 x 2 destination texels t, on each of which the integrand g(t)
// is constant. Hence, with the view's bilinear bin weights w_k,
//   value = (1/|P|) sum_t W(t) g(t),   W(t) = sum_k w_k area of {p in P : x'_k(p) in t},
// computed exactly from the overlaps. A footprint wider than a tile is folded: every source column
// (row) index modulo N enters once with its multiplicity, so the cost is O(min(|P|, N^2)) texels.
//
// C++17, standard library only. Internal to the evaluator library.
#pragma once

#include "eval/texel_shading.hpp"

namespace clothbake::eval {

// Footprints whose exact sum needs no dense weight map (at most this many source texels).
inline constexpr uint32_t kSmallExactSources = 64;

// The exact average over `footprint` (finite, x1 >= x0, y1 >= y0; a zero-area footprint is the
// point (x0, y0)). supersampling == 0: the exact partition; s > 0: s x s midpoint samples per
// source texel piece instead (converging to it, for tests). Adds to out->lobes and
// out->counters.texel_evals (out->value is left to the caller). Errors: Unsupported when the
// dense weight map (N x N doubles, for footprints of more than kSmallExactSources source texels)
// cannot be allocated.
Status exact_average(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                     uint32_t supersampling, Estimate* out) noexcept;

// Number of source texels (pieces of texels) the exact sum of `footprint` visits.
double exact_source_count(const EvalData& data, const Footprint& footprint) noexcept;

}  // namespace clothbake::eval

// The estimators behind Evaluator::estimate (one file each; docs/evaluator.md). Each adds its
// per-lobe parts to out->lobes and its costs to out->counters; the caller sums the value.
//
// C++17, standard library only, no allocation. Internal to the evaluator library.
#pragma once

#include "eval/texel_shading.hpp"

namespace clothbake::eval {

// Brute force (the paper's "w/o multi-scale"): one view bin drawn with its weight, then spp
// stratified points p in P, each shaded at its own x'_k(p) (per-texel parallax, Eq. 2). A
// zero-area P is the point (x0, y0): every sample there.
void brute_force(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                 uint32_t spp, Rng& rng, Estimate* out) noexcept;

// Eq. 8-10 as printed (MultiscalePaper): base terms from the Integral-Radiance tables and the
// footprint sums over the footprint shifted by its mean parallax offset, plus a residual of spp
// samples k G D (V - v_c) at p + mean offset. P has positive area; the specular tables are open.
// Errors: InvalidArgument from the parallax footprint query.
Status paper_control_variates(const EvalData& data, const ShadingFrame& frame,
                              const Footprint& footprint, uint32_t spp, Rng& rng,
                              Estimate* out) noexcept;

// The block A of whole periods the unbiased form integrates from its tables: kx by ky tiles at
// P's corner (x0, y0), each count ⌊w/N⌋ or ⌈w/N⌉ (and the same for h), at least 1, whichever pair
// makes the symmetric difference of A and P least. The rest of P is B = (P \ A) − (A \ P): at most
// two rectangles, the column between x0 + min(w, kx N) and x0 + max(w, kx N) and the row between
// y0 + min(h, ky N) and y0 + max(h, ky N) (over x0 .. x0 + min(w, kx N)), each added (+1) where P
// reaches beyond A and subtracted (−1) where A reaches beyond P, so that
//   ∫_P g = ∫_A g + Σ_r sign_r ∫_{rect_r} g.
// Allocation: none. Safe on any finite footprint of positive area.
struct PeriodBlock {
  double kx = 0, ky = 0;
  Footprint rects[2];        // the column, the row
  double areas[2] = {0, 0};  // 0 for a rectangle that is empty
  double signs[2] = {1, 1};
  double remainder = 0;  // (areas[0] + areas[1]) / |P|: |B| / |P|
};
PeriodBlock period_block(uint32_t n, const Footprint& footprint) noexcept;

// The unbiased form (Multiscale): one view bin drawn with its weight; the control variate g with
// each texel's low-rank visibility at every sample's own destination; its mean over P's block of
// whole periods (`block`, period_block(data.n, P)) from the bin's push-forward sums, over the rest
// from remainder_samples() cheap samples. P has positive area; the compressed specular tables are
// open. Errors: Unsupported when the bin's push-forward sums cannot be allocated.
Status pushforward_control_variates(const EvalData& data, const ShadingFrame& frame,
                                    const Footprint& footprint, const PeriodBlock& block,
                                    uint32_t spp, Rng& rng, Estimate* out) noexcept;

inline constexpr uint32_t kMaxRemainderSamples = 1u << 16;
// The cheap samples of g the unbiased form draws over B (`block` of the footprint) for spp samples
// (EvalOptions::remainder_sample_scale): at least 1 per rectangle of B that has an area; 0 when P
// is made of whole periods.
uint32_t remainder_samples(const EvalData& data, const PeriodBlock& block, uint32_t spp) noexcept;

}  // namespace clothbake::eval

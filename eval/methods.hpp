// The estimators behind Evaluator::estimate (one file each; docs/evaluator.md). Each adds its
// per-lobe parts to out->lobes and its costs to out->counters; the caller sums the value.
//
// C++17, standard library only, no allocation. Internal to the evaluator library.
#pragma once

#include "eval/footprint_cover.hpp"
#include "eval/texel_shading.hpp"

namespace clothbake::eval {

// Brute force (the paper's "w/o multi-scale"): one view bin drawn with its weight, then spp
// stratified points p in P, each shaded at its own x'_k(p) (per-texel parallax, Eq. 2). A
// zero-area P is the point (x0, y0): every sample there.
void brute_force(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                 uint32_t spp, Rng& rng, Estimate* out) noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // the single file leaves the paper's biased method out
// Eq. 8-10 as printed (MultiscalePaper): base terms from the Integral-Radiance tables and the
// footprint sums over the footprint shifted by its mean parallax offset, plus a residual of spp
// samples k G D (V - v_c) at p + mean offset. P has positive area; the specular tables are open.
// Errors: InvalidArgument from the parallax footprint query.
Status paper_control_variates(const EvalData& data, const ShadingFrame& frame,
                              const Footprint& footprint, uint32_t spp, Rng& rng,
                              Estimate* out) noexcept;
#endif

// The unbiased form (Multiscale): one view bin drawn with its weight; the control variate g with
// each texel's low-rank visibility at every sample's own destination, its integral over the
// cover's base region exact from the bin's tables (the whole-tile push-forward sums or the block
// prefix sums), over the cover's regions from remainder_samples() cheap samples, and the
// visibility correction g_V - g where EvalData::corrects_visibility; without a base, g_V itself
// (each texel's own visibility, fibre distribution and albedo) by cheap samples over P
// (footprint_cover.hpp). P has positive area; the compressed specular tables are open. Errors:
// Unsupported when the bin's sums cannot be allocated.
// When `moments` is not null, each residual point's f, g (as the forms with a base use it) and
// g_V are added to it: only the pilot's estimates (a cover without a base, no parallax) give it
// meaningful moments (visibility_pilot.hpp).
struct ResidualMoments;
Status pushforward_control_variates(const EvalData& data, const ShadingFrame& frame,
                                    const Footprint& footprint, const FootprintCover& cover,
                                    uint32_t spp, Rng& rng, Estimate* out,
                                    ResidualMoments* moments = nullptr) noexcept;

}  // namespace clothbake::eval

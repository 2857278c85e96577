// The estimators behind Evaluator::estimate (one file each; docs/evaluator.md). Each adds its
// per-lobe parts to out->lobes and its costs to out->counters; the caller sums the value.
//
// C++17, standard library only, no allocation. Internal to the evaluator library.
#pragma once

#include "eval/texel_shading.hpp"

namespace clothbake::eval {

// Brute force (the paper's "w/o multi-scale"): spp stratified points p in P, each shaded at its own
// x'(p) (per-texel parallax, Eq. 2). P has positive area.
void brute_force(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                 uint32_t spp, Rng& rng, Estimate* out) noexcept;

// Clustered control variates (Eq. 8-11): base terms from the Integral-Radiance tables and the
// footprint sums over the footprint shifted by its mean parallax offset, plus a residual of spp
// samples. paper_form: Eq. 8-10 as printed (residual k G D (V - v_c) at the shifted samples);
// otherwise the unbiased form (residual f(x'(p)) - g(p + mean offset)). P has positive area; the
// specular tables are open. weight in (0, 1]: the unbiased form's control-variate coefficient
// (Eq. 7's alpha: weight * base + residual of f - weight * g; any value keeps it unbiased); the
// paper form must be given 1 (its residual is not weighted). Errors: InvalidArgument from the
// parallax footprint query.
Status control_variates(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                        uint32_t spp, Rng& rng, bool paper_form, double weight,
                        Estimate* out) noexcept;

}  // namespace clothbake::eval

// Where the unbiased form's visibility correction pays: a pilot at open, per band of the light's
// elevation (docs/evaluator.md, "Where the correction pays"). C++17, standard library only.
#pragma once

#include "eval/evaluator.hpp"

namespace clothbake::eval {

struct EvalData;

// The residual points' moments that the pilot reads from an estimate (methods.hpp): per point x,
// the sums of x and x^2 of f - g, f - g_V and g_V - g (g as the forms with a base use it; a
// point's value: every lobe's mean of its three channels, summed), and the number of points.
struct ResidualMoments {
  enum Quantity { kResidual = 0, kCorrectedResidual, kCorrection };
  double sum[3] = {}, square[3] = {}, count = 0;
  void add(const Rgb* f, const Rgb* g, const Rgb* g_visibility) noexcept;
  // The sample variance of a quantity (divisor count - 1); needs count >= 2.
  double variance(Quantity q) const noexcept {
    return (square[q] - sum[q] * sum[q] / count) / (count - 1.0);
  }
};

// Sets data->visibility_pays for every band of |i_z| (EvalData::kVisibilityBands): per band, up to
// kPilotEstimates estimates of the unbiased form, each over a whole tile at a random offset with no
// base (no view bin's sums are built), one cheap sample and no parallax (no plane decoded), spp
// kPilotSpp, a reflection light with |i_z| uniform over the band and a view of o_z 1, 0.8, 0.55 or
// 0.3 in turn, azimuths and offsets from a generator of fixed seed; pairs whose half vector a
// scene-planned asset left out are drawn again, up to kPilotAttempts in all. With V_1, V_2, V_3 an
// estimate's sample variances over its residual points of f - g, f - g_V and g_V - g, the ratio of
// the variance of an estimate with a base with the correction to without it is
// (V_2 + V_3 / visibility_samples) / V_1 (its cheap samples cover a thin remainder). A band keeps
// the correction when the median ratio over its estimates with V_1 > 0 (as a relative error weighs
// them) is at most kCorrectionPays, when fewer than a quarter of kPilotEstimates estimates had
// V_1 > 0, and when an estimate fails. Deterministic for an asset and its options; needs the
// tables and texel records open (open() calls it last, when visibility_samples > 0 and
// visibility_pilot). A few ms on the 256^2 example bakes; allocates only what the estimates
// allocate. Not thread safe.
void run_visibility_pilot(EvalData* data) noexcept;

// Sets data->attenuation_pays for every band of min(|i_z|, |o_z|) (EvalData::kAttenuationBands):
// per band, kAttenuationPairs (24) reflection pairs, one direction in the band and the other above
// it, each over a square footprint of 0.15, 0.3 or 0.5 of a repeat a side at a random offset, no
// parallax, estimated 8 times at 2 spp by the form without a base with g_V's yarn attenuation and 8
// with each texel's own (docs/evaluator.md, "The attenuation g_V takes"). A band takes the texel's
// own when the sum over its pairs of the estimates' sample variances relative to the squared pooled
// mean, times 1.25 (its cost), is below the yarn's; the yarn's when fewer than a quarter of the
// pairs had a positive mean or an estimate fails. Deterministic for an asset and its options; 8-16
// ms on the 256^2 example bakes; allocates only what the estimates allocate. Not thread safe.
void run_attenuation_pilot(EvalData* data) noexcept;

}  // namespace clothbake::eval

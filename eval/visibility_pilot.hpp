// Where the unbiased form's visibility correction pays: a pilot at open, per band of the light's
// elevation (docs/evaluator.md, "Where the correction pays"). C++17, standard library only.
#pragma once

#include "eval/evaluator.hpp"

namespace clothbake::eval {

struct EvalData;

// The residual points' moments that the pilot reads from an estimate (methods.hpp), for both forms
// of g (kWithBase: the cluster's mean specular albedo, as the forms with a base use it;
// kWithoutBase: each texel's own): per point x, the sums of x and x^2 of f - g, f - g_V and g_V - g
// (a point's value: every lobe's mean of its three channels, summed), and the number of points per
// form. Each point is also paired with a partner floor(u0 + partner_side (u1 - u2)) texels away in
// x and likewise in y (uniforms from *partner_rng; u0 the point's place in its texel, which the
// estimate does not keep, drawn afresh), and half the squared difference of their g (without a
// base) is summed: the variance of g within a cheap sample's cell. Filled by estimates without a
// base or parallax.
struct ResidualMoments {
  enum Form { kWithBase = 0, kWithoutBase = 1 };
  enum Quantity { kResidual = 0, kCorrectedResidual, kCorrection };
  double sum[2][3] = {}, square[2][3] = {}, count[2] = {0, 0};
  double partner_side = 0, pair_square = 0, pairs = 0;
  Rng* partner_rng = nullptr;
  void add(Form form, const Rgb* f, const Rgb* g, const Rgb* g_visibility) noexcept;
  // The sample variance of a quantity (divisor count - 1); needs count >= 2.
  double variance(Form form, Quantity q) const noexcept {
    return (square[form][q] - sum[form][q] * sum[form][q] / count[form]) / (count[form] - 1.0);
  }
};

// Sets data->visibility_pays[form] (ResidualMoments::Form: with a base, without) for every
// band of |i_z| (EvalData::kVisibilityBands): per band, up to kPilotEstimates estimates of the
// unbiased form, each over a whole tile at a random offset with no base (no view bin's sums are
// built), one cheap sample and no parallax (no plane decoded), spp kPilotSpp, the correction on, a
// reflection light with |i_z| uniform over the band and a view of o_z 1, 0.8, 0.55 or 0.3 in turn,
// azimuths and offsets from a generator of fixed seed; pairs whose half vector a scene-planned
// asset left out are drawn again, up to kPilotAttempts in all. With V_1, V_2, V_3 an estimate's
// sample variances over its residual points of f - g, f - g_V and g_V - g, per form of g, the
// ratio of the estimate's variance with the correction to without it is, with a base,
// (V_2 + V_3 / visibility_samples) / V_1 (its cheap samples cover a thin remainder), and without,
// (V_2 + V_3 / visibility_samples + C) / (V_1 + C), C = (2 / m) W the cheap samples' variance per
// residual sample of a footprint kReferenceSide of a tile a side at 2 spp (m = remainder_samples
// there, W the variance of g within one of its m cells, from pairs of points a cell apart). A band
// keeps the correction when the median over its estimates with V_1 > 0 in both forms (as a relative
// error weighs them) is at most kCorrectionPays (kCorrectionPaysWithoutBase without a base), when
// fewer than a quarter of kPilotEstimates estimates had V_1 > 0, and when an estimate fails.
// Deterministic for an asset and its options; needs the tables and texel records open (open() calls
// it last, when visibility_samples > 0 and visibility_pilot). 3-5 ms on the 256^2 example bakes;
// allocates only what the estimates allocate. Not thread safe.
void run_visibility_pilot(EvalData* data) noexcept;

}  // namespace clothbake::eval

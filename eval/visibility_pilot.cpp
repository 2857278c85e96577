// The visibility correction's pilot (visibility_pilot.hpp).
#include "eval/visibility_pilot.hpp"

#include <algorithm>
#include <cmath>

#include "eval/eval_data.hpp"
#include "eval/footprint_cover.hpp"
#include "eval/methods.hpp"
#include "eval/texel_shading.hpp"

namespace clothbake::eval {
namespace {

constexpr uint32_t kPilotEstimates = 64;  // per band
// Directions drawn per band at most: a scene-planned asset answers only the half vectors it kept
// (those of its scene), and the pilot measures it there.
constexpr uint32_t kPilotAttempts = 32 * kPilotEstimates;
constexpr uint32_t kPilotSpp = 8;
constexpr double kViewZ[4] = {1.0, 0.8, 0.55, 0.3};  // the views' o_z, in turn
// The correction costs about as much as the rest of a 2-spp estimate (16 samples of 90-500 ns
// against 2-3 us), so it must at least halve the residual's variance to pay; the measured assets
// sit far on either side (docs/evaluator.md, "Where the correction pays").
constexpr double kCorrectionPays = 0.5;
// Without a base the cheap samples cost as much again as the residual's, so the correction adds
// about half to an estimate (the goose-eye chair's 2-spp render: 0.070 s with it, 0.048 s
// without): it pays when it removes a third of the variance.
constexpr double kCorrectionPaysWithoutBase = 2.0 / 3.0;
// The footprint whose cheap samples the pilot weighs for the form without a base: a quarter of the
// tile a side, between that form's least footprint (a tenth of a tile) and the blocks' (0.7).
constexpr double kReferenceSide = 0.25;
constexpr uint64_t kPilotSeed = 0x5eed'0f'7153'b11fULL;

// A direction with z uniform in [z0, z1] and a uniform azimuth.
void direction(double z0, double z1, Rng& rng, double out[3]) {
  const double z = z0 + (z1 - z0) * rng.uniform();
  const double phi = 2.0 * model::kPi<double> * rng.uniform();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  out[0] = r * std::cos(phi);
  out[1] = r * std::sin(phi);
  out[2] = z;
}

}  // namespace

void ResidualMoments::add(Form form, const Rgb* f, const Rgb* g, const Rgb* g_visibility) noexcept {
  double value[3] = {0, 0, 0};  // f - g, f - g_V, g_V - g
  for (int l = 0; l < model::kLobeCount; ++l) {
    value[kResidual] += (f[l] - g[l]).mean();
    value[kCorrectedResidual] += (f[l] - g_visibility[l]).mean();
    value[kCorrection] += (g_visibility[l] - g[l]).mean();
  }
  for (int i = 0; i < 3; ++i) {
    sum[form][i] += value[i];
    square[form][i] += value[i] * value[i];
  }
  count[form] += 1.0;
}

void run_visibility_pilot(EvalData* data) noexcept {
  const double n = double(data->n);
  const double kappa = double(data->options.visibility_samples);
  Rng rng(kPilotSeed), partner_rng(kPilotSeed + 1);  // partners apart: rng draws as before
  // The reference footprint's cheap samples at 2 spp: m of them on a jittered grid of cells of side
  // `stratum`, so their mean's variance per residual sample is (2 / m) W, W the variance of g
  // within a cell (half the mean squared difference of two points of one cell).
  const double side = kReferenceSide * n;
  const uint32_t m =
      std::max<uint32_t>(1, remainder_samples(*data, no_base_cover({0, 0, side, side}), 2));
  const double stratum = side / std::max(1.0, std::round(std::sqrt(double(m))));
  // Without parallax: f and g are compared at the same texel either way, and the parallax table's
  // planes are decoded only for the view bins a caller meets (decoding them here took 135-175 ms).
  const bool parallax = data->options.parallax;
  data->options.parallax = false;
  for (int band = 0; band < EvalData::kVisibilityBands; ++band) {
    const double z0 = std::max(0.02, double(band) / EvalData::kVisibilityBands);
    const double z1 = double(band + 1) / EvalData::kVisibilityBands;
    double ratios[2][kPilotEstimates];  // per form and estimate: its variance with / without
    uint32_t count = 0;
    bool failed = false;
    for (uint32_t e = 0; e < kPilotAttempts && count < kPilotEstimates; ++e) {
      double wi[3], wo[3];
      direction(z0, z1, rng, wi);
      direction(kViewZ[e % 4], kViewZ[e % 4], rng, wo);
      const double x = n * rng.uniform(), y = n * rng.uniform();
      ShadingFrame frame;
      Status status;
      Estimate estimate;
      ResidualMoments moments;
      moments.partner_side = stratum;
      moments.partner_rng = &partner_rng;
      if (!make_frame(*data, wi, wo, kAllLobes, &frame, &status)) continue;
      const double h[3] = {frame.h.x, frame.h.y, frame.h.z};
      if (!data->specular.tables->covers_bins(h)) continue;
      // One cheap sample: the pilot reads only the residual's points.
      const Footprint tile{x, y, x + n, y + n};
      FootprintCover cover = no_base_cover(tile);
      cover.remainder = 1e-12;
      if (!pushforward_control_variates(*data, frame, tile, cover, kPilotSpp, rng, &estimate,
                                        &moments)
               .ok()) {
        failed = true;
        break;
      }
      using M = ResidualMoments;
      if (moments.count[0] < 2.0 || !(moments.variance(M::kWithBase, M::kResidual) > 0.0) ||
          !(moments.variance(M::kWithoutBase, M::kResidual) > 0.0))
        continue;
      const double cheap[2] = {0.0, 2.0 / double(m) * moments.pair_square / moments.pairs};
      for (const M::Form form : {M::kWithBase, M::kWithoutBase})
        ratios[form][count] = (moments.variance(form, M::kCorrectedResidual) +
                               moments.variance(form, M::kCorrection) / kappa + cheap[form]) /
                              (moments.variance(form, M::kResidual) + cheap[form]);
      ++count;
    }
    const double threshold[2] = {kCorrectionPays, kCorrectionPaysWithoutBase};
    for (int form = 0; form < 2; ++form) {
      std::nth_element(ratios[form], ratios[form] + count / 2, ratios[form] + count);
      data->visibility_pays[form][band] =
          failed || count < kPilotEstimates / 4 || ratios[form][count / 2] <= threshold[form];
    }
  }
  data->options.parallax = parallax;
}

}  // namespace clothbake::eval

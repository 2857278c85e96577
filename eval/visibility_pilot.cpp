// The estimator's pilots: the visibility correction's and g_V's attenuation's
// (visibility_pilot.hpp).
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
// The correction adds about half to a 2-spp estimate (a whole 256^2 twill tile: 3.3-3.9 us with
// it, 2.0-2.4 us without), so it pays where it removes a third of the residual's variance
// (docs/evaluator.md, "Where the correction pays").
constexpr double kCorrectionPays = 2.0 / 3.0;
// g_V's attenuation pilot: per band, kAttenuationPairs direction pairs, each over a footprint of
// one of kAttenuationSides of a repeat a side (where the form without a base runs), estimated
// kAttenuationRepeats times at 2 spp with either attenuation. The texel's own costs about a
// quarter more per estimate of that form (182 cheap samples: 7.9 -> 9.8 us on the satin).
constexpr uint32_t kAttenuationPairs = 24, kAttenuationRepeats = 8;
constexpr double kAttenuationSides[3] = {0.15, 0.3, 0.5};
constexpr double kTexelAttenuationCost = 1.25;
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

// The frame of (wi, wo), when the tables answer its half vector (a scene-planned asset keeps only
// its scene's).
bool pilot_frame(const EvalData& data, const double wi[3], const double wo[3],
                 ShadingFrame* frame) {
  Status status;
  if (!make_frame(data, wi, wo, kAllLobes, frame, &status)) return false;
  const double h[3] = {frame->h.x, frame->h.y, frame->h.z};
  return data.specular.tables->covers_bins(h);
}

}  // namespace

void ResidualMoments::add(const Rgb* f, const Rgb* g, const Rgb* g_visibility) noexcept {
  double value[3] = {0, 0, 0};  // f - g, f - g_V, g_V - g
  for (int l = 0; l < model::kLobeCount; ++l) {
    value[kResidual] += (f[l] - g[l]).mean();
    value[kCorrectedResidual] += (f[l] - g_visibility[l]).mean();
    value[kCorrection] += (g_visibility[l] - g[l]).mean();
  }
  for (int i = 0; i < 3; ++i) {
    sum[i] += value[i];
    square[i] += value[i] * value[i];
  }
  count += 1.0;
}

void run_visibility_pilot(EvalData* data) noexcept {
  const double n = double(data->n);
  const double kappa = double(data->options.visibility_samples);
  Rng rng(kPilotSeed);
  // Without parallax: f and g are compared at the same texel either way, and the parallax table's
  // planes are decoded only for the view bins a caller meets (decoding them here took 135-175 ms).
  const bool parallax = data->options.parallax;
  data->options.parallax = false;
  for (int band = 0; band < EvalData::kVisibilityBands; ++band) {
    const double z0 = std::max(0.02, double(band) / EvalData::kVisibilityBands);
    const double z1 = double(band + 1) / EvalData::kVisibilityBands;
    double ratios[kPilotEstimates];  // per estimate: its variance with / without
    uint32_t count = 0;
    bool failed = false;
    for (uint32_t e = 0; e < kPilotAttempts && count < kPilotEstimates; ++e) {
      double wi[3], wo[3];
      direction(z0, z1, rng, wi);
      direction(kViewZ[e % 4], kViewZ[e % 4], rng, wo);
      const double x = n * rng.uniform(), y = n * rng.uniform();
      ShadingFrame frame;
      Estimate estimate;
      ResidualMoments moments;
      if (!pilot_frame(*data, wi, wo, &frame)) continue;
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
      if (moments.count < 2.0 || !(moments.variance(M::kResidual) > 0.0)) continue;
      ratios[count++] =
          (moments.variance(M::kCorrectedResidual) + moments.variance(M::kCorrection) / kappa) /
          moments.variance(M::kResidual);
    }
    std::nth_element(ratios, ratios + count / 2, ratios + count);
    data->visibility_pays[band] =
        failed || count < kPilotEstimates / 4 || ratios[count / 2] <= kCorrectionPays;
  }
  data->options.parallax = parallax;
}

void run_attenuation_pilot(EvalData* data) noexcept {
  const double n = double(data->n);
  Rng rng(kPilotSeed);
  const bool parallax = data->options.parallax;  // off, as the visibility pilot's
  data->options.parallax = false;
  bool failed = false;
  for (int band = 0; band < EvalData::kAttenuationBands; ++band) {
    const double z0 = std::max(0.05, double(band) / EvalData::kAttenuationBands);
    double weighted[2] = {0.0, 0.0};  // per attenuation, the sum of relative variances
    uint32_t pairs = 0;
    for (uint32_t e = 0; e < kPilotAttempts && pairs < kAttenuationPairs && !failed; ++e) {
      // One direction in the band, the other above it, either one the light.
      double a[3], b[3];
      direction(z0, double(band + 1) / EvalData::kAttenuationBands, rng, a);
      direction(z0, 1.0, rng, b);
      const bool light_first = rng.uniform() < 0.5;
      ShadingFrame frame;
      if (!pilot_frame(*data, light_first ? a : b, light_first ? b : a, &frame)) continue;
      const double side = n * kAttenuationSides[pairs % 3];
      const double x = n * rng.uniform(), y = n * rng.uniform();
      const Footprint p{x, y, x + side, y + side};
      // The same points for both (common random numbers): their variances' ratio is then measured
      // far more closely than from independent draws.
      const Rng points = rng;
      double sum[2] = {0.0, 0.0}, square[2] = {0.0, 0.0};
      for (int own = 0; own < 2; ++own) {
        data->attenuation_pays[band] = own == 1;
        rng = points;
        for (uint32_t r = 0; r < kAttenuationRepeats; ++r) {
          Estimate estimate;
          failed = failed || !pushforward_control_variates(*data, frame, p, no_base_cover(p), 2,
                                                           rng, &estimate)
                                  .ok();
          double value = 0.0;
          for (const Rgb& lobe : estimate.lobes)
            value += lobe.mean();
          sum[own] += value;
          square[own] += value * value;
        }
      }
      const double r = double(kAttenuationRepeats), mean = (sum[0] + sum[1]) / (2.0 * r);
      if (!(mean > 0.0)) continue;
      for (int own = 0; own < 2; ++own)
        weighted[own] += (square[own] - sum[own] * sum[own] / r) / ((r - 1.0) * mean * mean);
      ++pairs;
    }
    data->attenuation_pays[band] = !failed && pairs >= kAttenuationPairs / 4 &&
                                   weighted[1] * kTexelAttenuationCost < weighted[0];
  }
  data->options.parallax = parallax;
}

}  // namespace clothbake::eval

// Brute-force Monte Carlo over the footprint (methods.hpp).
#include <cmath>

#include "eval/footprint_samples.hpp"
#include "eval/methods.hpp"

namespace clothbake::eval {

void brute_force(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                 uint32_t spp, Rng& rng, Estimate* out) noexcept {
  Rgb sums[model::kLobeCount];
  TexelShading shading;
  // One view bin per estimate, drawn with its weight (the model's average over the four bins).
  const int bin = draw_view_bin(frame, rng.uniform());
  const BinShift shift = bin_shift(data, frame, bin);
  auto sample = [&](double x, double y) {
    // Eq. 2 with the bin's depth of the texel containing p, then every factor at the texel of x'.
    int64_t tx = 0, ty = 0;
    shifted_destination(shift, data.texel(int64_t(std::floor(x)), int64_t(std::floor(y))), x, y,
                        &tx, &ty);
    shade_texel(data, frame, tx, ty, &shading);
    for (int l = 0; l < model::kLobeCount; ++l)
      sums[l] += shading.lobes[l];
  };
  if (footprint.x1 > footprint.x0 && footprint.y1 > footprint.y0)
    stratified_points(footprint, spp, rng, sample);
  else  // a point: every sample there (only the view bin is random)
    for (uint32_t k = 0; k < spp; ++k)
      sample(footprint.x0, footprint.y0);
  for (int l = 0; l < model::kLobeCount; ++l)
    out->lobes[l] += sums[l] / double(spp);
  out->counters.samples += spp;
  out->counters.texel_evals += spp;
}

}  // namespace clothbake::eval

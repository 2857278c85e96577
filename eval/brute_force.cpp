// Brute-force Monte Carlo over the footprint (methods.hpp).
#include <cmath>

#include "eval/footprint_samples.hpp"
#include "eval/methods.hpp"

namespace clothbake::eval {

void brute_force(const EvalData& data, const ShadingFrame& frame, const Footprint& footprint,
                 uint32_t spp, Rng& rng, Estimate* out) noexcept {
  Rgb sums[model::kLobeCount];
  TexelShading shading;
  stratified_points(footprint, spp, rng, [&](double x, double y) {
    // Eq. 2 with the depth of the texel containing p, then every factor at the texel of x'.
    const double r = texel_depth(data, frame, int64_t(std::floor(x)), int64_t(std::floor(y)));
    const double xp = x + r * frame.offset_per_depth[0], yp = y + r * frame.offset_per_depth[1];
    shade_texel(data, frame, int64_t(std::floor(xp)), int64_t(std::floor(yp)), &shading);
    for (int l = 0; l < model::kLobeCount; ++l)
      sums[l] += shading.lobes[l];
  });
  for (int l = 0; l < model::kLobeCount; ++l)
    out->lobes[l] += sums[l] / double(spp);
  out->counters.samples += spp;
  out->counters.texel_evals += spp;
}

}  // namespace clothbake::eval

// Stratified sample points over a footprint for the Monte Carlo methods (docs/evaluator.md,
// "Sampling the footprint").
//
// spp points: an nx x ny jittered grid whose cells follow the footprint's aspect ratio
// (nx * ny <= spp), plus the remaining spp - nx * ny points uniform over the footprint. Every grid
// cell holds one point uniform in it, so the mean of g over all spp points is an unbiased estimate
// of the footprint average of g, and the grid removes most of the variance between cells.
//
// C++17, standard library only, no allocation. Internal to the evaluator library.
#pragma once

#include <cmath>
#include <cstdint>

#include "eval/evaluator.hpp"

namespace clothbake::eval {

// Calls visit(x, y) for spp points in `p` (x1 > x0, y1 > y0), drawing 2 numbers of rng per point.
template <class Visit>
void stratified_points(const Footprint& p, uint32_t spp, Rng& rng, Visit visit) {
  const double w = p.x1 - p.x0, h = p.y1 - p.y0;
  double cols = std::round(std::sqrt(double(spp) * w / h));
  if (!(cols >= 1.0)) cols = 1.0;
  if (cols > double(spp)) cols = double(spp);
  const uint32_t nx = uint32_t(cols);
  const uint32_t ny = spp / nx;
  for (uint32_t j = 0; j < ny; ++j)
    for (uint32_t i = 0; i < nx; ++i) {
      const double u = (double(i) + rng.uniform()) / double(nx);
      const double v = (double(j) + rng.uniform()) / double(ny);
      visit(p.x0 + u * w, p.y0 + v * h);
    }
  for (uint32_t k = nx * ny; k < spp; ++k) {
    const double u = rng.uniform(), v = rng.uniform();
    visit(p.x0 + u * w, p.y0 + v * h);
  }
}

}  // namespace clothbake::eval

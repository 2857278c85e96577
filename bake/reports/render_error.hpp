// relMSE of renders against a reference, as the reports define it (docs/rendering.md, "Error
// against run time"; docs/scene-plans.md, "Proof"): the mean over pixels and channels of
// (x - r)^2 / (r^2 + eps^2), eps = 1 % of the reference's mean over the pixels compared (a floor,
// so that nearly black pixels do not dominate). Shared by `report error-time` and `report plan`.
#pragma once

#include <cstdint>
#include <vector>

#include "render/renderer.hpp"

namespace clothbake::reports {

// eps^2 of the definition above over the pixels of `mask` (all when empty); 1e-12 for a black
// reference.
double relmse_floor(const render::RenderResult& ref, const std::vector<uint8_t>& mask);

// relMSE of `a` against `ref` over the pixels of `mask` (all when empty); 0 without pixels.
double masked_relmse(const render::RenderResult& a, const render::RenderResult& ref,
                     const std::vector<uint8_t>& mask);

// The relMSE between the expected values of two renders, estimated without bias from two
// independent pairs (a1, b1), (a2, b2): the mean over the pixels of `mask` and their channels of
// (a1 - b1)(a2 - b2) / (r^2 + eps^2). The pairs' noise is independent, so its products average to
// zero; where a pair shares its random numbers and the two renders agree, its difference is exactly
// zero. Can be slightly negative. The standard error treats pixels as independent (a pixel's three
// channels come from the same samples, so they are averaged first).
struct MeanAndError {
  double mean = 0, std_error = 0;
};
MeanAndError relmse_of_means(const render::RenderResult& a1, const render::RenderResult& b1,
                             const render::RenderResult& a2, const render::RenderResult& b2,
                             const render::RenderResult& ref, const std::vector<uint8_t>& mask);

// The term of relmse_of_means at pixel p (its channels averaged), with floor2 = relmse_floor(ref,
// mask): for maps of where two expected pictures differ.
double relmse_of_means_term(const render::RenderResult& a1, const render::RenderResult& b1,
                            const render::RenderResult& a2, const render::RenderResult& b2,
                            const render::RenderResult& ref, std::size_t p, double floor2);

// relMSE between two renders a and b with the reference's normalisation: the mean over the pixels
// of `mask` and their channels of (a - b)^2 / (r^2 + eps^2) (relmse_of_means with one pair).
double relmse_between(const render::RenderResult& a, const render::RenderResult& b,
                      const render::RenderResult& ref, const std::vector<uint8_t>& mask);

// The relMSE of `a` against the expected value of a reference that is known only from two
// independent renders t1, t2 of it at equal spp (the path-traced truth of `report error-time`),
// with the reference's own noise removed: relMSE(a, t) - relmse_between(t1, t2, t) / 4, where
// t = (t1 + t2) / 2 (the caller's, all four the same size) gives the weights. With a, t1, t2
// independent, E[(a - t)^2] = E[(a - mu)^2] + var t and E[(t1 - t2)^2] = 4 var t. Clamped at 0
// (below only by noise, when `a` is as converged as t). Its one bias is the weights' noise
// (1 / (t^2 + eps^2) against 1 / (mu^2 + eps^2)): about 3 (sigma_t / mu)^2 relative, 0.3 % for a
// truth whose pixels have 3 % noise.
double relmse_against_noisy(const render::RenderResult& a, const render::RenderResult& t1,
                            const render::RenderResult& t2, const render::RenderResult& t,
                            const std::vector<uint8_t>& mask);

}  // namespace clothbake::reports

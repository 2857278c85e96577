// relMSE of renders (render_error.hpp).
#include "bake/reports/render_error.hpp"

#include <algorithm>
#include <cmath>

namespace clothbake::reports {

double relmse_floor(const render::RenderResult& ref, const std::vector<uint8_t>& mask) {
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t k = 0; k < ref.rgb.size(); ++k)
    if (mask.empty() || mask[k / 3]) sum += ref.rgb[k], ++count;
  const double eps = 0.01 * (count ? sum / count : 0.0);
  return eps > 0 ? eps * eps : 1e-12;
}

double masked_relmse(const render::RenderResult& a, const render::RenderResult& ref,
                     const std::vector<uint8_t>& mask) {
  const double floor2 = relmse_floor(ref, mask);
  double rel = 0;
  std::size_t count = 0;
  for (std::size_t k = 0; k < ref.rgb.size(); ++k) {
    if (!mask.empty() && !mask[k / 3]) continue;
    const double d = double(a.rgb[k]) - ref.rgb[k];
    rel += d * d / (double(ref.rgb[k]) * ref.rgb[k] + floor2);
    ++count;
  }
  return count ? rel / count : 0;
}

MeanAndError relmse_of_means(const render::RenderResult& a1, const render::RenderResult& b1,
                             const render::RenderResult& a2, const render::RenderResult& b2,
                             const render::RenderResult& ref, const std::vector<uint8_t>& mask) {
  const double floor2 = relmse_floor(ref, mask);
  double rel = 0, rel2 = 0;
  std::size_t pixels = 0;
  for (std::size_t p = 0; 3 * p < ref.rgb.size(); ++p) {
    if (!mask.empty() && !mask[p]) continue;
    const double term = relmse_of_means_term(a1, b1, a2, b2, ref, p, floor2);
    rel += term;
    rel2 += term * term;
    ++pixels;
  }
  if (pixels == 0) return {};
  const double n = double(pixels), mean = rel / n;
  const double var = pixels > 1 ? std::max(0.0, (rel2 - n * mean * mean) / (n - 1)) : 0.0;
  return {mean, std::sqrt(var / n)};
}

double relmse_of_means_term(const render::RenderResult& a1, const render::RenderResult& b1,
                            const render::RenderResult& a2, const render::RenderResult& b2,
                            const render::RenderResult& ref, std::size_t p, double floor2) {
  double term = 0;
  for (std::size_t k = 3 * p; k < 3 * p + 3; ++k) {
    const double d1 = double(a1.rgb[k]) - b1.rgb[k], d2 = double(a2.rgb[k]) - b2.rgb[k];
    term += d1 * d2 / (double(ref.rgb[k]) * ref.rgb[k] + floor2) / 3;
  }
  return term;
}

double relmse_between(const render::RenderResult& a, const render::RenderResult& b,
                      const render::RenderResult& ref, const std::vector<uint8_t>& mask) {
  return relmse_of_means(a, b, a, b, ref, mask).mean;
}

double relmse_against_noisy(const render::RenderResult& a, const render::RenderResult& t1,
                            const render::RenderResult& t2, const render::RenderResult& t,
                            const std::vector<uint8_t>& mask) {
  return std::max(0.0, masked_relmse(a, t, mask) - 0.25 * relmse_between(t1, t2, t, mask));
}

}  // namespace clothbake::reports

// The relMSE of the reports against a noisy reference (bake/reports/render_error.hpp), on synthetic
// images whose noise is known: the correction removes the reference's own variance and nothing
// else.
#include <gtest/gtest.h>

#include <random>

#include "bake/reports/render_error.hpp"

using namespace clothbake;

namespace {

// A w x h image whose every value is mean(p) + N(0, sigma * mean(p)), mean varying over pixels.
render::RenderResult noisy(int w, int h, double sigma, std::mt19937_64& rng) {
  render::RenderResult r;
  r.width = w;
  r.height = h;
  r.rgb.resize(std::size_t(w) * h * 3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (std::size_t k = 0; k < r.rgb.size(); ++k) {
    const double mean = 0.5 + double(k % 97) / 97.0;
    r.rgb[k] = float(mean * (1 + sigma * n(rng)));
  }
  return r;
}

render::RenderResult average(const render::RenderResult& a, const render::RenderResult& b) {
  render::RenderResult t = a;
  for (std::size_t k = 0; k < t.rgb.size(); ++k)
    t.rgb[k] = 0.5f * (a.rgb[k] + b.rgb[k]);
  return t;
}

}  // namespace

// a has 10 % noise (relMSE 0.01 against its mean); the truth's halves have as much as a, so a's
// relMSE against their average is 0.015 uncorrected, and 0.01 corrected. With 60 000 values the
// estimates' standard error is about 1e-4; the weights' noise biases them by 3 * 0.0707^2 / 2 of
// 0.01 (0.08 %).
TEST(RelmseAgainstNoisy, RemovesTheReferencesNoiseAndOnlyThat) {
  std::mt19937_64 rng(7);
  const int w = 200, h = 100;
  const std::vector<uint8_t> all;  // every pixel
  for (double sigma_truth : {0.1, 0.02}) {
    const render::RenderResult a = noisy(w, h, 0.1, rng);
    const render::RenderResult t1 = noisy(w, h, sigma_truth, rng);
    const render::RenderResult t2 = noisy(w, h, sigma_truth, rng);
    const render::RenderResult t = average(t1, t2);
    const double raw = reports::masked_relmse(a, t, all);
    const double corrected = reports::relmse_against_noisy(a, t1, t2, t, all);
    const double truth_variance = sigma_truth * sigma_truth / 2;
    EXPECT_NEAR(raw, 0.01 + truth_variance, 5e-4) << sigma_truth;
    EXPECT_NEAR(corrected, 0.01, 5e-4) << sigma_truth;
  }
  // Against itself as converged as the truth, the estimate is clamped at 0, never negative.
  const render::RenderResult t1 = noisy(w, h, 0.1, rng), t2 = noisy(w, h, 0.1, rng);
  const render::RenderResult t = average(t1, t2);
  EXPECT_EQ(reports::relmse_against_noisy(t, t1, t2, t, all), 0.0);
  // A mask keeps only its pixels: every masked-out pixel of `a` broken changes nothing.
  render::RenderResult a = noisy(w, h, 0.1, rng);
  std::vector<uint8_t> left(std::size_t(w) * h, 0);
  for (int p = 0; p < w * h; ++p)
    left[std::size_t(p)] = p % w < w / 2;
  const double before = reports::relmse_against_noisy(a, t1, t2, t, left);
  for (int p = 0; p < w * h; ++p)
    if (!left[std::size_t(p)]) a.rgb[3 * std::size_t(p)] = 1e6f;
  EXPECT_EQ(reports::relmse_against_noisy(a, t1, t2, t, left), before);
}

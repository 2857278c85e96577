// Where the variance of the unbiased control variates comes from (docs/evaluator.md, "Variance:
// what limits it"): on a whole-tile footprint, for a few view directions and one light direction,
// the per-sample standard deviation (uniform samples p over the tile) of
//   f        f(x'(p)), the brute-force integrand;
//   aligned  f(x'(p)) - f(x'(p)) v_c / V: a control variate at the sample's own destination texel
//            that only replaces V by the cluster mean (what a parallax-aware table would leave);
//   shifted  f(x'(p)) - the same control variate at p + mean offset (the estimator's coupling).
//
//   eval_variance_study ASSET [--light x,y,z] [--samples N]
// Uses the evaluator's internal headers (eval/texel_shading.hpp); exit 2 on a bad asset.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "eval/eval_data.hpp"
#include "eval/evaluator.hpp"
#include "eval/texel_shading.hpp"

using namespace clothbake;
using namespace clothbake::eval;

namespace {

double total(const TexelShading& s) {
  double v = 0;
  for (const Rgb& l : s.lobes)
    v += l.mean();
  return v;
}

// f with V replaced by the cluster mean (0 where V = 0: no light reaches the texel).
double with_mean_visibility(const ShadingFrame& frame, const TexelShading& s) {
  return s.visibility > 0 ? total(s) * frame.mean_visibility[s.label] / s.visibility : 0.0;
}

struct Moments {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double v) { sum += v, sum2 += v * v, ++n; }
  double sd() const { return std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n))); }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: eval_variance_study ASSET [--light x,y,z] [--samples N]\n");
    return 2;
  }
  double light[3] = {0.3, 0.2, 0.9};
  int samples = 200000;
  for (int a = 2; a + 1 < argc; a += 2) {
    const std::string opt = argv[a];
    if (opt == "--light" &&
        std::sscanf(argv[a + 1], "%lf,%lf,%lf", &light[0], &light[1], &light[2]) == 3)
      continue;
    if (opt == "--samples" && (samples = std::atoi(argv[a + 1])) > 0) continue;
    std::fprintf(stderr, "eval_variance_study: bad option %s\n", opt.c_str());
    return 2;
  }
  reader::Asset asset;
  Evaluator ev;
  Status s = asset.open_file(argv[1]);
  if (s.ok()) s = ev.open(asset);
  if (!s.ok()) {
    std::fprintf(stderr, "eval_variance_study: %s\n", s.message());
    return 2;
  }
  const EvalData& d = *evaluator_data(ev);
  const double n = d.n;
  std::printf("asset %s, light (%g, %g, %g), %d uniform samples over the tile\n", argv[1], light[0],
              light[1], light[2], samples);
  std::printf("%-22s %10s %10s %10s %10s %10s\n", "view", "max offset", "sd f", "aligned",
              "shifted", "f ratio^2");
  const double views[][3] = {
      {-0.1, 0.1, 0.99}, {-0.4, 0.1, 0.85}, {-0.7, 0.1, 0.7}, {0.5, 0.5, 0.7}};
  for (const auto& wo : views) {
    ShadingFrame frame;
    if (!make_frame(d, light, wo, kAllLobes, &frame, &s)) return 2;
    const Footprint tile{0, 0, n, n};
    reader::ParallaxSample mean;
    const double view[3] = {frame.view.x, frame.view.y, frame.view.z};
    d.parallax.footprint_depth(tile, view, &mean);
    const double dx = mean.offset[0] * n, dy = mean.offset[1] * n;
    double max_offset = 0;
    for (int64_t y = 0; y < int64_t(n); ++y)
      for (int64_t x = 0; x < int64_t(n); ++x) {
        const double r = texel_depth(d, frame, x, y);
        max_offset = std::max(
            max_offset, std::hypot(r * frame.offset_per_depth[0], r * frame.offset_per_depth[1]));
      }
    Rng rng(3);
    Moments f, aligned, shifted;
    TexelShading at_x, at_shift;
    for (int k = 0; k < samples; ++k) {
      const double x = rng.uniform() * n, y = rng.uniform() * n;
      const double r = texel_depth(d, frame, int64_t(std::floor(x)), int64_t(std::floor(y)));
      shade_texel(d, frame, int64_t(std::floor(x + r * frame.offset_per_depth[0])),
                  int64_t(std::floor(y + r * frame.offset_per_depth[1])), &at_x);
      shade_texel(d, frame, int64_t(std::floor(x + dx)), int64_t(std::floor(y + dy)), &at_shift);
      const double fx = total(at_x);
      f.add(fx);
      aligned.add(fx - with_mean_visibility(frame, at_x));
      shifted.add(fx - with_mean_visibility(frame, at_shift));
    }
    char name[64];
    std::snprintf(name, sizeof name, "(%g, %g, %g)", wo[0], wo[1], wo[2]);
    std::printf("%-22s %10.2f %10.4f %10.4f %10.4f %10.1f\n", name, max_offset, f.sd(),
                aligned.sd(), shifted.sd(), (f.sd() / shifted.sd()) * (f.sd() / shifted.sd()));
  }
  return 0;
}

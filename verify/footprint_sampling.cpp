// Random footprints by size class (footprint_sampling.hpp).
#include "verify/footprint_sampling.hpp"

#include <algorithm>
#include <cmath>

#include "model/splitmix64.hpp"

namespace clothbake::verify {

std::vector<SizeClass> size_classes(int n) {
  const double size = double(n);
  std::vector<SizeClass> all = {{"1", 1, 2},
                                {"2", 2, 4},
                                {"4", 4, 16},
                                {"16", 16, 64},
                                {"64", 64, size},
                                {"tile", size, 2 * size},
                                {"tiles", 2 * size, 5 * size}};
  std::vector<SizeClass> out;
  for (auto& c : all) {
    c.max_side = c.name == "tile" || c.name == "tiles" ? c.max_side : std::min(c.max_side, size);
    if (c.max_side > c.min_side) out.push_back(c);
  }
  return out;
}

std::vector<SampledFootprint> sample_footprints(int n, int count, uint64_t seed) {
  const auto classes = size_classes(n);
  model::SplitMix64 rng(seed);
  std::vector<SampledFootprint> out;
  for (int i = 0; i < count; ++i) {
    SampledFootprint f;
    f.size_class = i % int(classes.size());
    const SizeClass& c = classes[std::size_t(f.size_class)];
    // Half vector: uniform over the upper hemisphere.
    const double z = rng.uniform(), phi = 2 * M_PI * rng.uniform(), r = std::sqrt(1 - z * z);
    f.h[0] = r * std::cos(phi);
    f.h[1] = r * std::sin(phi);
    f.h[2] = z;
    if (i == 0) {
      f.rect = {double(n - 1), double(n - 1), double(n), double(n)};
      out.push_back(f);
      continue;
    }
    // Side log-uniform in the class, aspect in [1/2, 2], anywhere in [-3N, 3N)^2.
    const double side = c.min_side * std::pow(c.max_side / c.min_side, rng.uniform());
    const double aspect = std::pow(2.0, 2 * rng.uniform() - 1);
    double w = side * std::sqrt(aspect), h = side / std::sqrt(aspect);
    double x0 = (rng.uniform() * 6 - 3) * n, y0 = (rng.uniform() * 6 - 3) * n;
    if (rng.uniform() < 0.5) {  // texel-aligned corners half of the time
      x0 = std::floor(x0);
      y0 = std::floor(y0);
      w = std::max(1.0, std::round(w));
      h = std::max(1.0, std::round(h));
    }
    f.rect = {x0, y0, x0 + w, y0 + h};
    out.push_back(f);
  }
  return out;
}

std::vector<double> axis_coverage(double a0, double a1, int n) {
  std::vector<double> w(std::size_t(n), 0.0);
  if (!(a1 > a0)) return w;
  const double span = a1 - a0;
  // Whole periods first (each column gets one unit per period), then the remainder.
  const double periods = std::floor(span / n);
  for (double& v : w)
    v = periods;
  const double b0 = a0, b1 = a0 + (span - periods * n);
  for (double i = std::floor(b0); i < b1; i += 1.0) {
    const double lo = std::max(b0, i), hi = std::min(b1, i + 1.0);
    if (hi <= lo) continue;
    long m = long(std::fmod(i, double(n)));
    if (m < 0) m += n;
    w[std::size_t(m)] += hi - lo;
  }
  return w;
}

}  // namespace clothbake::verify

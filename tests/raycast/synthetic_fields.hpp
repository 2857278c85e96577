// Height fields for the ray-casting tests and benchmarks, defined analytically so that expected
// values can be derived in closed form (tests) or so that the workload looks like a woven tile
// (benchmarks). Heights are in tile-side units, sampled at texel centres u = (x + 0.5) / N.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "fabric/fabric.hpp"

namespace clothbake::raycast::rctest {

inline FabricMaps maps_from(int n, const std::function<double(double, double)>& height) {
  FabricMaps maps;
  maps.resolution = n;
  maps.height.resize(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      maps.height[std::size_t(y) * n + x] = float(height((x + 0.5) / n, (y + 0.5) / n));
  return maps;
}

// A plain weave with `threads` warp and weft threads per tile: elliptic yarn cross-sections of
// half-width `width / 2` (in thread spacings), crimped with amplitude `crimp`, thickness
// `thickness` (all in tile-side units except width). Gaps between yarns are at height 0.
inline FabricMaps plain_weave_maps(int n, int threads = 4, double thickness = 0.06,
                                   double crimp = 0.03, double width = 0.85) {
  const double pi = 3.14159265358979323846;
  return maps_from(n, [=](double u, double v) {
    auto yarn = [&](double across, double along, int parity) {
      double s = across * threads;  // in spacings
      double k = std::floor(s);
      double off = (s - k - 0.5) / (width / 2);
      if (std::abs(off) >= 1) return 0.0;
      int index = int(k);
      double phase = ((index + parity) % 2 == 0) ? 0.0 : pi;
      double centre = crimp * (1 + std::cos(2 * pi * along * threads / 2 + phase)) / 2;
      return thickness * 0.5 + centre + thickness * 0.5 * std::sqrt(1 - off * off);
    };
    return std::max(yarn(u, v, 0), yarn(v, u, 1));
  });
}

}  // namespace clothbake::raycast::rctest

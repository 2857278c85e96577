// Synthetic inputs for the table, raw-reader and verify tests: a small periodic "weave" of
// tangents, roughness per yarn, gaps and a label map, with no dependency on the fabric loader.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "tables/radiance_fill.hpp"

namespace clothbake::tables_testing {
using namespace clothbake::tables;

struct SyntheticFabric {
  int n = 0;
  std::vector<Vec3f> tangent;
  std::vector<float> gap;
  std::vector<uint16_t> yarn;
  std::vector<double> roughness;
  std::vector<uint8_t> labels;
  int clusters = 0;
  RadianceInputs inputs() const { return {n, tangent, gap, yarn, roughness, labels, clusters}; }
};

// Warp yarns (along y) in even bands, weft (along x) in odd ones, twisted tangents varying over
// the texel, a gap line every 8 texels (with partial gaps beside it), labels by 4 x 4 blocks.
inline SyntheticFabric synthetic_fabric(int n, int clusters, double warp_roughness = 0.3,
                                        double weft_roughness = 0.2, bool gaps = true) {
  SyntheticFabric f;
  f.n = n;
  f.clusters = clusters;
  f.roughness = {warp_roughness, weft_roughness};
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const bool warp = ((x / 4) + (y / 4)) % 2 == 0;
      const float phase = float(2 * M_PI * (warp ? x : y) / 8.0);
      const float tilt = 0.6f * std::sin(phase), twist = 0.3f * std::cos(phase);
      Vec3f t = warp ? Vec3f{twist, 1.0f, tilt} : Vec3f{1.0f, twist, tilt};
      f.tangent.push_back(t);
      f.yarn.push_back(warp ? 0 : 1);
      float g = 1.0f;
      if (gaps && x % 8 == 7) g = 0.0f;
      if (gaps && x % 8 == 6) g = 0.5f;
      f.gap.push_back(g);
      f.labels.push_back(uint8_t(((x / 4) * 3 + (y / 4) * 5) % clusters));
    }
  return f;
}

// Closed form of the hemisphere integral of the fibre-like SGGX D (any tangent):
// sigma + atan(sqrt(1 - sigma^2) / sigma) / sqrt(1 - sigma^2) (half the sphere's).
inline double sggx_hemisphere_integral(double sigma) {
  if (sigma >= 1.0) return 2.0;
  const double k = std::sqrt(1.0 - sigma * sigma);
  return sigma + std::atan(k / sigma) / k;
}

}  // namespace clothbake::tables_testing

// Shared helpers of the compress, reader and verify tests: synthetic directional data, direct
// footprint sums.
#pragma once

#include <cmath>
#include <vector>

#include "compress/compressed_set.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress::test {

// Covered length of each texel column of a periodic axis of n texels by [a0, a1).
inline std::vector<double> coverage(double a0, double a1, int n) {
  std::vector<double> c(std::size_t(n), 0.0);
  double start = std::floor(a0);
  for (double t = start; t < a1; t += 1.0) {
    const double lo = std::max(a0, t), hi = std::min(a1, t + 1.0);
    if (hi <= lo) continue;
    const long long k = (long long)t;
    const int idx = int(((k % n) + n) % n);
    c[std::size_t(idx)] += hi - lo;
  }
  return c;
}

// Direct F_c(rect, h) of every cluster from per-texel values (texels x bins) and labels.
inline std::vector<double> direct_sums(const std::vector<float>& values,
                                       const std::vector<uint8_t>& cluster, int n,
                                       int bins_per_side, int clusters,
                                       const reader::Footprint& rect, const double h[3]) {
  reader::BinWeights bw;
  EXPECT_TRUE(reader::radiance_bin_weights(uint32_t(bins_per_side), h, &bw).ok());
  const std::vector<double> cx = coverage(rect.x0, rect.x1, n), cy = coverage(rect.y0, rect.y1, n);
  const std::size_t bins = std::size_t(bins_per_side) * std::size_t(bins_per_side);
  std::vector<double> out(std::size_t(clusters), 0.0);
  for (int y = 0; y < n; ++y) {
    if (cy[std::size_t(y)] == 0) continue;
    for (int x = 0; x < n; ++x) {
      if (cx[std::size_t(x)] == 0) continue;
      const std::size_t t = std::size_t(y) * std::size_t(n) + std::size_t(x);
      if (cluster[t] == 255) continue;
      double v = 0;
      for (uint32_t w = 0; w < bw.count; ++w)
        v += bw.weight[w] * double(values[t * bins + bw.bin[w]]);
      out[cluster[t]] += cx[std::size_t(x)] * cy[std::size_t(y)] * v;
    }
  }
  return out;
}

// Smooth positive synthetic tables: `clusters` label blocks, lobes whose direction varies with
// the texel, a few zero texels.
inline DirectionalTexels synthetic_texels(int n, int bins_per_side, int clusters, uint64_t seed) {
  DirectionalTexels d;
  d.kind =
      bins_per_side == 1 ? reader::RadianceTableKind::Gap : reader::RadianceTableKind::Specular;
  d.resolution = n;
  d.bins_per_side = bins_per_side;
  d.cluster_count = clusters;
  d.samples_per_bin_side = bins_per_side == 1 ? 0 : 2;
  d.lobes = 1;
  const std::size_t texels = std::size_t(n) * std::size_t(n), bins = std::size_t(d.bins());
  d.cluster.resize(texels);
  d.values.resize(texels * bins);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const std::size_t t = std::size_t(y) * std::size_t(n) + std::size_t(x);
      d.cluster[t] = uint8_t(((x / 5) + (y / 7) + int(seed)) % clusters);
      const double phase = 0.3 * x + 0.2 * y + double(seed);
      for (std::size_t b = 0; b < bins; ++b) {
        const double u = double(b % std::size_t(bins_per_side)) / bins_per_side;
        const double v = double(b / std::size_t(bins_per_side)) / bins_per_side;
        d.values[t * bins + b] =
            float(1.0 + 0.8 * std::sin(phase + 3 * u) * std::cos(2 * v - 0.5 * phase) +
                  0.3 * std::exp(-8 * (u - 0.5 + 0.2 * std::sin(phase)) * (u - 0.5)));
      }
      if ((x * 7 + y * 3) % 23 == 0)
        for (std::size_t b = 0; b < bins; ++b)
          d.values[t * bins + b] = 0.0f;
    }
  mark_zero_texels(&d);
  return d;
}

// An in-memory asset holding `sections` (kept alive by the returned buffer).
struct MemoryAsset {
  std::vector<std::byte> bytes;
  reader::Asset asset;
};
inline std::unique_ptr<MemoryAsset> memory_asset(const std::vector<formats::Section>& sections) {
  auto m = std::make_unique<MemoryAsset>();
  m->bytes = formats::serialize_asset(sections);
  const reader::Status s = m->asset.open_memory(m->bytes.data(), m->bytes.size());
  EXPECT_TRUE(s.ok()) << s.message();
  return m;
}

}  // namespace clothbake::compress::test

// SAT precision study (docs/tables.md, "Precision"): how exactly can a stored summed-area table of
// Integral-Radiance values answer footprint sums, for each storage the issue lists?
//
//   float     : SAT accumulated in double, stored as float (4 B)
//   float-dev : the paper's normalisation: S(x, y) - m x y (m the table mean), stored as float;
//               m x y added back in double at query time (4 B)
//   float-blk : per-block offsets: 16 x 16 blocks, S - S(block corner) as float plus one double
//               corner per block (4 B + 8 B / 256 texels)
//   u32-fixed : clothbake's choice: exact integer SAT of texels quantised to sum(T) / 2^32 steps
//               (4 B); u64-fixed the same with 2^62 (8 B)
//   double    : SAT stored as double (8 B)
//
// Tables: real bin-averaged SGGX values of a synthetic weave (satin roughness 0.04 and 0.3 yarns),
// masked to one of 8 visibility clusters, at the half-vector bin of the highlight and at a tail
// bin; 256^2 and 2048^2 texels. Error of a footprint: |F - direct| / max(direct, A * mean), direct
// the double sum of the same texel values, A the area, mean the table's mean texel value.
//   build-*/bin/sat_precision_study
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "tables/fixed_point_sat.hpp"
#include "tables/radiance_fill.hpp"

using namespace clothbake;
using namespace clothbake::tables;

namespace {

struct Weave {
  int n;
  std::vector<Vec3f> tangent;
  std::vector<float> gap;
  std::vector<uint16_t> yarn;
  std::vector<double> roughness{0.04, 0.3};
  std::vector<uint8_t> labels;
  RadianceInputs inputs() const { return {n, tangent, gap, yarn, roughness, labels, 8}; }
};

Weave weave(int n) {
  Weave w;
  w.n = n;
  const int period = std::max(8, n / 16);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const bool warp = ((x / period) + (y / period)) % 2 == 0;
      const float phase = float(2 * M_PI * (warp ? x : y) / (2.0 * period));
      w.tangent.push_back(warp ? Vec3f{0.2f * std::cos(phase), 1.0f, 0.7f * std::sin(phase)}
                               : Vec3f{1.0f, 0.2f * std::cos(phase), 0.7f * std::sin(phase)});
      w.yarn.push_back(warp ? 0 : 1);
      w.gap.push_back(x % (2 * period) == 2 * period - 1 ? 0.0f : 1.0f);
      const int b = std::max(1, n / 32);
      w.labels.push_back(uint8_t(((x / b) * 3 + (y / b) * 5) % 8));
    }
  return w;
}

// Every storage answers S(i, j) for i, j in [0, N] (exclusive SAT) as a double.
struct Storage {
  std::string name;
  double bytes_per_entry;
  std::vector<double> value;  // (N+1)^2 reconstructed corner values
};

std::vector<Storage> storages(int n, const std::vector<double>& t) {
  const std::size_t m = std::size_t(n) + 1;
  std::vector<double> exact(m * m, 0.0);
  for (int j = 1; j <= n; ++j) {
    double row = 0;
    for (int i = 1; i <= n; ++i) {
      row += t[std::size_t(j - 1) * n + std::size_t(i - 1)];
      exact[std::size_t(j) * m + std::size_t(i)] =
          exact[std::size_t(j - 1) * m + std::size_t(i)] + row;
    }
  }
  double total = exact.back(), mean = total / (double(n) * n);
  std::vector<Storage> out;
  Storage f{"float", 4, exact}, dev{"float-dev", 4, exact}, blk{"float-blk", 4 + 8.0 / 256, exact},
      dbl{"double", 8, exact};
  for (std::size_t k = 0; k < exact.size(); ++k)
    f.value[k] = double(float(exact[k]));
  for (std::size_t j = 0; j < m; ++j)
    for (std::size_t i = 0; i < m; ++i) {
      const double plane = mean * double(i) * double(j);
      dev.value[j * m + i] = double(float(exact[j * m + i] - plane)) + plane;
      const std::size_t ci = i / 16 * 16, cj = j / 16 * 16;
      const double corner = exact[cj * m + ci];
      blk.value[j * m + i] = double(float(exact[j * m + i] - corner)) + corner;
    }
  out.push_back(f);
  out.push_back(dev);
  out.push_back(blk);
  for (int bits : {32, 64}) {
    std::vector<float> v(t.begin(), t.end());
    std::vector<int16_t> col(t.size(), 0);
    double vt = 0;
    for (float x : v)
      vt += x;
    std::vector<double> totals = {vt};
    double unit;
    std::vector<uint64_t> sat(t.size());
    std::vector<std::byte> raw(t.size() * std::size_t(bits / 8));
    build_fixed_point_sat(n, v, col, totals, bits, &unit, raw.data());
    Storage s{bits == 32 ? "u32-fixed" : "u64-fixed", double(bits / 8), exact};
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        uint64_t q = 0;
        if (i > 0 && j > 0) {
          const std::size_t idx = std::size_t(j - 1) * n + std::size_t(i - 1);
          if (bits == 32) {
            uint32_t x;
            std::memcpy(&x, raw.data() + 4 * idx, 4);
            q = x;
          } else {
            std::memcpy(&q, raw.data() + 8 * idx, 8);
          }
        }
        s.value[std::size_t(j) * m + std::size_t(i)] = double(q) * unit;
      }
    out.push_back(s);
  }
  out.push_back(dbl);
  return out;
}

void study(const char* label, int n, const std::vector<double>& t) {
  const std::size_t m = std::size_t(n) + 1;
  double mean = 0;
  for (double v : t)
    mean += v / (double(n) * n);
  auto st = storages(n, t);
  std::printf("\n%s (N = %d, mean texel %.4g, max %.4g)\n", label, n, mean,
              *std::max_element(t.begin(), t.end()));
  std::printf("| footprint | %-10s", "");
  for (auto& s : st)
    std::printf("| %-18s", s.name.c_str());
  std::printf("|\n");
  std::mt19937_64 rng(1);
  for (int size : {1, 2, 4, 16, 64, n / 2}) {
    std::vector<double> worst(st.size(), 0.0), sq(st.size(), 0.0);
    int count = 0;
    for (int trial = 0; trial < 4000; ++trial) {
      int x0 = int(rng() % uint64_t(n - size + 1)), y0 = int(rng() % uint64_t(n - size + 1));
      if (trial == 0) x0 = y0 = n - size;  // the far corner
      const int x1 = x0 + size, y1 = y0 + size;
      auto at = [&](const std::vector<double>& s, int i, int j) {
        return s[std::size_t(j) * m + std::size_t(i)];
      };
      double direct = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
          direct += t[std::size_t(y) * n + std::size_t(x)];
      const double floor = double(size) * size * mean;
      for (std::size_t k = 0; k < st.size(); ++k) {
        const double q = at(st[k].value, x1, y1) - at(st[k].value, x0, y1) -
                         at(st[k].value, x1, y0) + at(st[k].value, x0, y0);
        const double e = std::abs(q - direct) / std::max(direct, floor);
        worst[k] = std::max(worst[k], e);
        sq[k] += e * e;
      }
      ++count;
    }
    std::printf("| %4d^2 max | %-8s", size, "");
    for (std::size_t k = 0; k < st.size(); ++k)
      std::printf("| %-18.2e", worst[k]);
    std::printf("|\n| %4d^2 rms | %-8s", size, "");
    for (std::size_t k = 0; k < st.size(); ++k)
      std::printf("| %-18.2e", std::sqrt(sq[k] / count));
    std::printf("|\n");
  }
  std::printf("| bytes/entry |         ");
  for (auto& s : st)
    std::printf("| %-18.3g", s.bytes_per_entry);
  std::printf("|\n");
}

std::vector<double> masked_bin(const Weave& w, int bin, int bins_per_side, int cluster) {
  const HalfVectorBins bins = make_half_vector_bins(bins_per_side, 4);
  std::vector<float> v(std::size_t(w.n) * w.n);
  radiance_bin_values(reader::RadianceTableKind::Specular, w.inputs(), bins, bin, v.data());
  std::vector<double> t(v.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    t[i] = w.labels[i] == cluster ? double(v[i]) : 0.0;
  return t;
}

}  // namespace

int main() {
  std::printf("SAT precision study: max / RMS of |F - direct| / max(direct, A * mean)\n");
  const Weave w256 = weave(256);
  // Bin (16, 16) of 32^2 is near the pole (the highlight of flat yarns); bin (0, 0) a grazing tail.
  study("256^2, cluster 3, highlight bin (16,16) of 32^2", 256,
        masked_bin(w256, 16 * 32 + 16, 32, 3));
  study("256^2, cluster 3, grazing bin (0,0) of 32^2", 256, masked_bin(w256, 0, 32, 3));
  const Weave w2048 = weave(2048);
  std::vector<double> t = masked_bin(w2048, 16 * 32 + 16, 32, 3);
  study("2048^2, cluster 3, highlight bin (16,16) of 32^2", 2048, t);
  return 0;
}

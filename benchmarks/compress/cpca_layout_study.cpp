// Study behind the C-PCA layout (docs/compression.md, "Layout"): on one fabric's specular tables
// with stand-in visibility clusters (k-means on folded tangent and yarn), the per-cluster spectra
// of the texel layout (centred energy left at each rank) and the footprint errors of a rank-r
// reconstruction, or with "sat", the same for the paper's whole-SAT layout (raw and normalised).
//
//   cpca_layout_study FABRIC.toml [RESOLUTION [BINS [sat]]]    (defaults 256, 32)
//
// Not part of the product; random footprints come from the project's SplitMix64 (seed 7).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "benchmarks/compress/stand_in_clusters.hpp"
#include "compress/randomized_svd.hpp"
#include "model/splitmix64.hpp"
#include "tables/half_vector_bins.hpp"
#include "tables/radiance_fill.hpp"

using namespace clothbake;
using Clock = std::chrono::steady_clock;
static double secs(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// A whole-string integer in [lo, hi], or exit 1 naming the argument.
static int int_argument(const char* text, const char* name, int lo, int hi) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < lo || v > hi) {
    std::fprintf(stderr, "cpca_layout_study: %s must be an integer in [%d, %d], got '%s'\n", name,
                 lo, hi, text);
    std::exit(1);
  }
  return int(v);
}

int main(int argc, char** argv) {
  if (argc < 2 || argc > 5 || (argc == 5 && std::strcmp(argv[4], "sat") != 0)) {
    std::fprintf(stderr, "usage: cpca_layout_study FABRIC.toml [RESOLUTION [BINS [sat]]]\n");
    return 1;
  }
  const char* path = argv[1];
  int res = argc > 2 ? int_argument(argv[2], "RESOLUTION", 8, 1024) : 256;
  int nbins = argc > 3 ? int_argument(argv[3], "BINS", 1, 256) : 32;
  LoadOptions lo;
  lo.resolution = res;
  auto loaded = load_fabric_description(path, lo);
  Fabric& f = loaded.fabric;
  const int n = f.maps.resolution;
  const std::size_t texels = std::size_t(n) * n;
  const studies::StandInClusters km = studies::stand_in_clusters(f.maps);
  const std::vector<uint8_t>& labels = km.labels;
  auto in = tables::radiance_inputs(f, labels, km.clusters);
  double minr = tables::min_roughness_in_use(in.view);
  int s = tables::default_samples_per_side(nbins, minr);
  auto bins = tables::make_half_vector_bins(nbins, s);
  const int B = bins.bin_count();
  auto t0 = Clock::now();
  std::vector<float> X(texels * B), col(texels);
  for (int b = 0; b < B; ++b) {
    tables::radiance_bin_values(tables::RadianceTableKind::Specular, in.view, bins, b, col.data());
    for (std::size_t t = 0; t < texels; ++t)
      X[t * B + b] = col[t];
  }
  std::printf("fill %.2fs, clusters %d, minr %.3f s %d\n", secs(t0), km.clusters, minr, s);
  std::vector<std::vector<uint32_t>> members(km.clusters);
  for (std::size_t t = 0; t < texels; ++t)
    members[labels[t]].push_back(uint32_t(t));

  if (argc > 4 && std::strcmp(argv[4], "sat") == 0) {
    const int C = km.clusters;
    const std::size_t NN = texels;
    const int T = C * B;
    for (int norm = 0; norm < 2; ++norm) {
      std::vector<float> S(std::size_t(T) * NN);
      std::vector<double> mval(T), off(T), scl(T);
      std::vector<double> sat((n + 1) * (n + 1));
      for (int c = 0; c < C; ++c)
        for (int b = 0; b < B; ++b) {
          int tb = c * B + b;
          std::fill(sat.begin(), sat.end(), 0.0);
          for (int y = 0; y < n; ++y) {
            double row = 0;
            for (int x = 0; x < n; ++x) {
              std::size_t t = std::size_t(y) * n + x;
              row += labels[t] == c ? X[t * B + b] : 0.0;
              sat[(y + 1) * (n + 1) + x + 1] = sat[y * (n + 1) + x + 1] + row;
            }
          }
          double m = sat[n * (n + 1) + n] / double(NN);
          mval[tb] = m;
          double lo = 1e300, hi = -1e300;
          for (int y = 1; y <= n; ++y)
            for (int x = 1; x <= n; ++x) {
              double v = sat[y * (n + 1) + x] - (norm ? m * x * y : 0.0);
              lo = std::min(lo, v);
              hi = std::max(hi, v);
            }
          off[tb] = norm ? lo : 0.0;
          scl[tb] = norm ? std::max(hi - lo, 1e-30) : 1.0;
          for (int y = 1; y <= n; ++y)
            for (int x = 1; x <= n; ++x) {
              double v = sat[y * (n + 1) + x] - (norm ? m * x * y : 0.0);
              S[std::size_t(tb) * NN + std::size_t(y - 1) * n + x - 1] =
                  float((v - off[tb]) / scl[tb]);
            }
        }
      std::vector<float> mean(NN, 0.f);
      {
        std::vector<double> acc(NN, 0.0);
        for (int tb = 0; tb < T; ++tb)
          for (std::size_t i = 0; i < NN; ++i)
            acc[i] += S[std::size_t(tb) * NN + i];
        for (std::size_t i = 0; i < NN; ++i)
          mean[i] = float(acc[i] / T);
      }
      compress::RowSubsetMatrix a{S.data(), std::size_t(T), NN, {}, mean};
      for (int r : {10, 40, 80}) {
        compress::RandomizedSvdOptions so;
        so.rank = r;
        so.power_iterations = 2;
        auto t1 = Clock::now();
        auto svd = compress::randomized_svd(a, so);
        compress::RowMatrixF Cf;
        compress::project_rows(a, svd.basis, &Cf);
        Eigen::MatrixXf Vf = svd.basis.cast<float>();
        double tsvd = secs(t1);
        // footprint errors with random integer rects (corner values reconstructed)
        auto recon = [&](int tb, int x,
                         int y) -> double {  // SAT at exclusive corner (x,y) in [0,n]
          if (x == 0 || y == 0) return 0.0;
          std::size_t i = std::size_t(y - 1) * n + x - 1;
          double v = mean[i];
          for (int j = 0; j < svd.rank; ++j)
            v += double(Cf(tb, j)) * Vf(i, j);
          return scl[tb] * v + off[tb] + (norm ? mval[tb] * x * y : 0.0);
        };
        model::SplitMix64 rng(7);
        std::printf("sat norm=%d rank %d (svd %.1fs):", norm, r, tsvd);
        for (int size : {1, 2, 4, 8, 16, 64}) {
          double se = 0, sf = 0;
          for (int q = 0; q < 3000; ++q) {
            int x0 = int(rng.below(n - size + 1)), y0 = int(rng.below(n - size + 1)),
                b = int(rng.below(B)), c = int(rng.below(C));
            int tb = c * B + b;
            double F = 0;
            for (int y = y0; y < y0 + size; ++y)
              for (int x = x0; x < x0 + size; ++x) {
                std::size_t t = std::size_t(y) * n + x;
                if (labels[t] == c) F += X[t * B + b];
              }
            double G = recon(tb, x0 + size, y0 + size) - recon(tb, x0, y0 + size) -
                       recon(tb, x0 + size, y0) + recon(tb, x0, y0);
            se += (G - F) * (G - F);
            sf += F * F;
          }
          std::printf("  %d^2: %.4f", size, std::sqrt(se / sf));
        }
        std::printf("\n");
      }
    }
    return 0;
  }
  int R = 64;
  std::vector<int> ranks = {1, 2, 4, 8, 12, 16, 24, 32, 48, 64};
  // per cluster spectra (centred)
  std::vector<std::vector<float>> means(km.clusters);
  std::vector<Eigen::MatrixXd> bases(km.clusters);
  for (int c = 0; c < km.clusters; ++c) {
    auto& m = members[c];
    means[c].assign(B, 0.f);
    std::vector<double> acc(B, 0.0);
    for (auto t : m)
      for (int b = 0; b < B; ++b)
        acc[b] += X[t * B + b];
    for (int b = 0; b < B; ++b)
      means[c][b] = float(acc[b] / m.size());
    compress::RowSubsetMatrix a{X.data(), texels, std::size_t(B), m, means[c]};
    compress::RandomizedSvdOptions so;
    so.rank = R;
    auto t1 = Clock::now();
    auto svd = compress::randomized_svd(a, so);
    // uncentred energy
    double e_unc = 0;
    for (auto t : m)
      for (int b = 0; b < B; ++b)
        e_unc += double(X[t * B + b]) * X[t * B + b];
    std::printf("cluster %d: %zu texels, svd %.2fs, centred/uncentred energy %.3f |", c, m.size(),
                secs(t1), svd.total_energy / e_unc);
    double kept = 0;
    int ri = 0;
    for (int j = 0; j < svd.rank; ++j) {
      kept += svd.singular[j] * svd.singular[j];
      if (ri < (int)ranks.size() && j + 1 == ranks[ri]) {
        std::printf(" r%d:%.4f", ranks[ri],
                    std::sqrt(std::max(0.0, e_unc - (svd.total_energy - kept)) > 0
                                  ? (svd.total_energy - kept) / e_unc
                                  : 0));
        ++ri;
      }
    }
    std::printf("\n");
    bases[c] = svd.basis;
  }
  // footprint errors for texel-layout rank r per cluster
  model::SplitMix64 rng(7);
  for (int r : {4, 8, 16, 32}) {
    // reconstruct
    std::vector<float> Y(texels * B);
    for (int c = 0; c < km.clusters; ++c) {
      Eigen::MatrixXd V = bases[c].leftCols(std::min<int>(r, bases[c].cols()));
      compress::RowSubsetMatrix a{X.data(), texels, std::size_t(B), members[c], means[c]};
      compress::RowMatrixF C;
      compress::project_rows(a, V, &C);
      Eigen::MatrixXf Vf = V.cast<float>();
      for (std::size_t i = 0; i < members[c].size(); ++i) {
        Eigen::VectorXf rec = Vf * C.row(i).transpose();
        for (int b = 0; b < B; ++b)
          Y[members[c][i] * B + b] = means[c][b] + rec[b];
      }
    }
    std::printf("rank %d:", r);
    for (int size : {1, 2, 4, 8, 16, 64}) {
      double se = 0, sf = 0, se_all = 0, sf_all = 0;
      for (int q = 0; q < 3000; ++q) {
        int x0 = int(rng.below(n)), y0 = int(rng.below(n)), b = int(rng.below(B)),
            c = int(rng.below(km.clusters));
        double F = 0, G = 0, Fa = 0, Ga = 0;
        for (int y = y0; y < y0 + size; ++y)
          for (int x = x0; x < x0 + size; ++x) {
            std::size_t t = std::size_t(y % n) * n + (x % n);
            Fa += X[t * B + b];
            Ga += Y[t * B + b];
            if (labels[t] == c) {
              F += X[t * B + b];
              G += Y[t * B + b];
            }
          }
        se += (G - F) * (G - F);
        sf += F * F;
        se_all += (Ga - Fa) * (Ga - Fa);
        sf_all += Fa * Fa;
      }
      std::printf("  %d^2: %.4f (sum %.4f)", size, std::sqrt(se / sf), std::sqrt(se_all / sf_all));
    }
    std::printf("\n");
  }
}

// ASG embedding weight study (docs/tables.md, "ASG embedding"): the share of the per-texel
// visibility variance that 8 clusters explain, for several weightings of the embedding's
// parameter groups, on the visibility lobes of baked assets (mean and range over 4 k-means++
// seeds: single runs differ by a few percent between local optima).
//   build-*/bin/embedding_weight_study ASSET.cbk [ASSET.cbk ...]
#include <algorithm>
#include <cstdio>
#include <vector>

#include "cluster/visibility_clusters.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/visibility_sections.hpp"

using namespace clothbake;

int main(int argc, char** argv) {
  struct Weights {
    const char* name;
    cluster::AsgEmbeddingWeights w;
  };
  const Weights variants[] = {
      {"axis 1, bandwidth 0.5, amplitude 1 (default)", {1.0, 0.5, 1.0}},
      {"axis 1, bandwidth 1, amplitude 1", {1.0, 1.0, 1.0}},
      {"axis 1, bandwidth 0.25, amplitude 1", {1.0, 0.25, 1.0}},
      {"axis 1, bandwidth 0.25, amplitude 2", {1.0, 0.25, 2.0}},
      {"axis 0.5, bandwidth 0.25, amplitude 1", {0.5, 0.25, 1.0}},
      {"axis 2, bandwidth 0.5, amplitude 1", {2.0, 0.5, 1.0}},
      {"axis 1, bandwidth 0.5, amplitude 0 (paper: axis, rotation, bandwidth)", {1.0, 0.5, 0.0}},
      {"axis 0, bandwidth 0, amplitude 1 (amplitude only)", {0.0, 0.0, 1.0}},
  };
  for (int a = 1; a < argc; ++a) {
    reader::Asset asset;
    if (!asset.open_file(argv[a]).ok()) {
      std::fprintf(stderr, "cannot open %s\n", argv[a]);
      return 2;
    }
    reader::VisibilityAsgView view;
    if (!view.open(asset).ok()) {
      std::fprintf(stderr, "%s has no visibility lobes\n", argv[a]);
      return 2;
    }
    const int n = int(view.resolution());
    std::vector<model::AsgParams<float>> lobes;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const auto p = view.lobe(x, y);
        lobes.push_back({model::Vec3f(p.axis), float(p.rotation), float(p.lambda), float(p.mu),
                         float(p.amplitude)});
      }
    std::printf("%s (%d^2 texels)\n", argv[a], n);
    for (const auto& v : variants) {
      double sum = 0, lo = 1, hi = 0;
      for (uint64_t seed = 1; seed <= 4; ++seed) {
        cluster::VisibilityClusterOptions o;
        o.weights = v.w;
        o.visibility_dirs = 16;
        o.seed = seed;
        const double e = cluster::cluster_visibility(n, lobes, o).explained_fraction;
        sum += e;
        lo = std::min(lo, e);
        hi = std::max(hi, e);
      }
      std::printf("  %-70s explained %.3f  [%.3f, %.3f]\n", v.name, sum / 4, lo, hi);
    }
  }
  return 0;
}

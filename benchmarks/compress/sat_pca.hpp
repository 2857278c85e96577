// The paper's layout (Sec. 4.4), for comparison in the study sat_layout_study.cpp (study code, not
// part of the product: clothbake stores the per-texel layout, compress/compressed_set.hpp): every
// table (stored visibility cluster c, half-vector bin b) is one vector, its summed-area table over
// the N x N tile, optionally normalised (sat_normalise.hpp); C-PCA (compress/cpca.hpp, one stratum)
// groups the C x B vectors into k clusters, each a mean SAT plus a rank-r basis of SATs, and stores
// per table its cluster, its r coefficients and its normalisation.
//
// Storage as counted here: every mean/basis image at 2 bytes per texel (IEEE half after division
// by its largest magnitude, exactly what the model evaluates with), per table 4 bytes per
// coefficient plus 3 doubles of normalisation. Queries bilinearly interpolate the reconstructed
// SAT at the footprint's corners (the same formula as formats/reader/radiance_query.hpp).
//
// Memory: C x B x N^2 floats while fitting (2 GiB at 8 x 32^2 x 256^2), so the study runs this
// layout at a reduced resolution by default. C++20; deterministic for any thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "benchmarks/compress/sat_normalise.hpp"
#include "compress/directional_texels.hpp"
#include "formats/reader/radiance_query.hpp"

namespace clothbake::compress {

struct SatPcaOptions {
  int clusters = 4;  // k (the paper: 4)
  int rank = 10;     // r (the paper: 10)
  SatNormalisation normalisation = SatNormalisation::PlaneUnit;
  int iterations = 2;
  uint64_t seed = 1;
};

class SatPcaModel {
 public:
  // Fits the model to `data`. Errors: as clustered_pca.
  static SatPcaModel fit(const DirectionalTexels& data, const SatPcaOptions& options);

  int resolution() const { return n_; }
  int bins_per_side() const { return bins_per_side_; }
  int cluster_count() const { return cluster_count_; }
  uint64_t stored_bytes() const;  // as counted above
  // Mean squared error of the normalised SAT values before quantisation: the paper's "MSE".
  double normalised_mse() const { return normalised_mse_; }
  int groups() const { return int(group_rank_.size()); }

  // Reconstructed inclusive SAT of table (column k, bin b) at exclusive corner (i, j) in [0, N]^2.
  double corner(int column, int bin, int i, int j) const;
  // F_c(rect, h) of cluster c (0 for clusters without tables); false for bad arguments.
  bool query(const reader::Footprint& rect, const double h[3], int cluster, double* out) const;

 private:
  double sat_at(int table, double x, double y) const;

  int n_ = 0, bins_per_side_ = 0, cluster_count_ = 0, max_rank_ = 0;
  std::vector<int> column_of_cluster_;      // cluster_count entries, -1 when not stored
  std::vector<int> table_group_;            // per table (column * bins + bin)
  std::vector<SatTransform> transform_;     // per table
  std::vector<float> coefficients_;         // per table: max_rank_ values (zero padded)
  std::vector<int> group_rank_;             // per group
  std::vector<std::vector<float>> images_;  // per group: (1 + r) images of N^2, mean first
  double normalised_mse_ = 0.0;
};

}  // namespace clothbake::compress

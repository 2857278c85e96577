// Low-rank visibility per cluster for the multi-scale control variate (docs/evaluator.md, "The
// error budget"; docs/tables.md, "Visibility basis").
//
// The paper's clustered control variate replaces every texel's visibility V(x, i) by its cluster's
// mean v_c(i) (Eq. 8). Measured on whole tiles, that one constant per cluster leaves 10 to 25 times
// less variance than brute force at best, whatever the rest of the control variate does; the
// texels' own visibility is what is missing. This fits, per cluster c, the mean and the leading
// principal components of the texels' visibility over light directions,
//
//   V(x, l) = clamp(G_x(w_l), 0, 1)                     (G_x the texel's ASG, w_l the centre of
//                                                        bin l of DirectionGrid{n, 0})
//   V(x, l) ~ m_c(l) + sum_{k=1..M} e_k(x) b_ck(l)        (c the cluster of x)
//
// with b_ck the unit eigenvectors of the cluster's covariance over the n^2 bins, in order of
// decreasing eigenvalue (sign: the entry of largest magnitude is positive), and
// e_k(x) = sum_l (V(x, l) - m_c(l)) b_ck(l). A renderer interpolates m_c and b_ck bilinearly
// between bin centres for its light direction, so the control variate carries every texel's own
// visibility up to rank M, and its integral is a per-cluster sum of M + 1 terms.
//
// Texels with identical ASG parameters (a woven tile repeats its relief) are fitted once, with
// their count as weight. Deterministic for any thread count (clusters are independent tasks, each
// summed in texel order). C++20; uses Eigen and TBB.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "model/asg.hpp"

namespace clothbake::cluster {

inline constexpr int kMaxVisibilityRank = 16;

struct VisibilityBasis {
  int resolution = 0;  // N
  int clusters = 0;    // C
  int dirs = 0;        // n: n x n bins of DirectionGrid{n, 0}
  int rank = 0;        // M
  // [c][k][bin], k = 0 the cluster mean m_c, k = 1..M the components b_ck: C (M + 1) n^2 values.
  std::vector<float> components;
  // [texel][k - 1], k = 1..M: N^2 M coefficients e_k(x) (empty when M = 0).
  std::vector<float> coefficients;
  // Per cluster: the share of its visibility variance (over texels and bins) that the M components
  // capture, in [0, 1] (1 for a cluster without variance).
  std::vector<double> explained_fraction;
};

// Fits the basis for the N x N texels' ASGs (row-major) and their cluster labels (< clusters).
// Errors (clothbake::Error, Input): sizes that do not match N, clusters outside [1, 255], a label
// out of range, dirs outside [1, 256], rank outside [0, kMaxVisibilityRank].
VisibilityBasis fit_visibility_basis(int resolution, std::span<const model::AsgParams<float>> asgs,
                                     std::span<const uint8_t> labels, int clusters, int dirs,
                                     int rank);

}  // namespace clothbake::cluster

// Fit of one LTC sheen lobe (model/sheen.hpp: M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]] in the frame
// of wo) to the simulated distribution of exit directions of the sheen layer.
//
// Objective: the squared L2 distance between the two densities over the hemisphere, with the
// simulation's density piecewise constant per ExitBinning bin,
//   E(a, b) = sum_k (p_k - P_k(a, b))^2 / Omega_k,
// where p_k is the fraction of reflected paths in bin k, P_k the LTC probability of the bin
// (Gauss-Legendre quadrature of model::sheen_ltc_density, the function the renderer evaluates)
// and Omega_k its solid angle. Monte Carlo noise in p_k is zero-mean, so it adds a constant to the
// expected objective and does not bias the minimiser (an L3 or relative loss would).
// Minimised by Nelder-Mead over (log a, b), from several starting points.
#pragma once

#include <array>
#include <vector>

#include "sheen/sheen_layer.hpp"

namespace clothbake::sheen {

// Quadrature nodes of the LTC density over the bins of an ExitBinning (both halves of each bin).
// The density is model::sheen_ltc_density for a wo in the xz plane, written out so that it
// vectorises (a test checks the two agree).
class LtcBinQuadrature {
 public:
  // nodes_per_axis Gauss-Legendre nodes in z and in phi per bin (1 to 4).
  explicit LtcBinQuadrature(const ExitBinning& binning, int nodes_per_axis = 3);

  const ExitBinning& binning() const { return binning_; }
  // Solid angle of each bin, both halves (they sum to 2 pi).
  const std::vector<double>& bin_solid_angles() const { return solid_angle_; }
  // Probability of each bin under the LTC lobe (a, b). The lobe lives in the frame of wo, so it
  // does not depend on the elevation of wo.
  void bin_probabilities(double a, double b, std::vector<double>& out) const;

 private:
  // Nodes of bin k are [k * nodes_per_bin_, (k + 1) * nodes_per_bin_), stored as arrays so that
  // the inner loop vectorises.
  ExitBinning binning_;
  int nodes_per_bin_ = 0;
  std::vector<double> x_, y_, z_, weight_;  // weight: solid angle, doubled for the mirrored half
  std::vector<double> solid_angle_;
};

struct LtcFit {
  double a = 1.0, b = 0.0;
  double objective = 0.0;  // E(a, b) at the optimum, 1/sr
  double l1_error = 0.0;   // sum_k |p_k - P_k|: twice the total-variation distance, noise included
  int evaluations = 0;
};

// Fits (a, b) to the bin probabilities `target` (sum 1). Each start is (a, b) with a > 0; the best
// local optimum wins. fix_b_zero fits a alone with b = 0 (wo
// at the pole, where the lobe must be rotationally symmetric).
LtcFit fit_ltc_lobe(const std::vector<double>& target, const LtcBinQuadrature& quadrature,
                    const std::vector<std::array<double, 2>>& starts, bool fix_b_zero);

// The L1 distance sum_k |p_k - P_k| expected from multinomial noise alone when the fit is exact:
// sum_k sqrt(2 P_k (1 - P_k) / (pi N)) for N reflected paths (normal approximation).
double expected_noise_l1(const std::vector<double>& target, uint64_t reflected_paths);

}  // namespace clothbake::sheen

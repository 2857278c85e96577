// Least-squares fit of one anisotropic spherical Gaussian (model/asg.hpp) to sampled binary
// visibility (docs/raycast.md, "ASG fit").
//
// Given K directions d_k of equal solid angle on the upper hemisphere and V_k in {0, 1}, finds
// axis, rotation, bandwidths and amplitude minimising sum_k (G(d_k) - V_k)^2, and reports the RMS
// error sqrt(sum / K) (the solid-angle RMS, since the samples have equal solid angle).
//
// Method (deterministic, bounded, fixed budget): texels that see all or none of the sampled sky get
// an exact closed form (axis +z, bandwidths 0, amplitude 1 or 0, error 0). Otherwise two starts are
// scored (a lobe from the moments of the visible directions: axis = their mean, bandwidths from
// their spread about it; and the best zero-bandwidth lobe, i.e. half-space, with its axis tilted
// towards the mean, found by golden-section search since gradients cannot move a cut plane) and the
// better one is refined by Levenberg-Marquardt (Eigen, 6 parameters: a rotation increment of the
// frame, lambda, mu, c) with at most kAsgFitMaxRefinements trial steps; every step is projected
// into the bounds (bandwidths [0, kAsgMaxBandwidth], amplitude [0, kAsgMaxAmplitude], axis in the
// upper hemisphere) and accepted only if it lowers the objective, so the fit cannot diverge.
#pragma once

#include <cstdint>
#include <vector>

#include "model/asg.hpp"
#include "model/vec.hpp"

namespace clothbake::raycast {

// The sample directions of a fit, as structure of arrays (unit vectors, z >= 0). Single
// precision: the per-sample passes are vectorised in float (Eigen arrays); sums, the normal
// equations and the parameters are double.
struct FitDirections {
  std::vector<float> x, y, z;
  std::size_t size() const { return x.size(); }
  void push_back(double dx, double dy, double dz) {
    x.push_back(float(dx));
    y.push_back(float(dy));
    z.push_back(float(dz));
  }
};

struct AsgFitResult {
  model::AsgParams<double> params;  // canonical (lambda >= mu, rotation in [0, pi))
  double rms_error = 0.0;           // of the fitted (unquantised) lobe
  int evaluations = 0;              // objective evaluations used (<= kMaxEvaluations)
};

// Objective evaluations: 14 for the half-space search, 2 to score the starts, then at most
// kAsgFitMaxRefinements Levenberg-Marquardt trial steps (it stops earlier once a step improves the
// objective by less than 1e-4 of its value). Measured on a woven tile: 8 steps reach a mean RMS
// error within 0.2 % of 24 steps (docs/raycast.md).
inline constexpr int kAsgFitMaxRefinements = 8;
inline constexpr int kAsgFitMaxEvaluations = 14 + 2 + kAsgFitMaxRefinements;

// Knobs for studies of the fit (benchmarks/raycast/asg_fit_study.cpp); the bake uses defaults.
struct AsgFitOptions {
  int max_refinements = kAsgFitMaxRefinements;  // LM trial steps per start
  int random_starts = 0;        // extra random starts, each refined; the best result is kept
  uint64_t seed = 1;            // of the random starts
  bool xu_smooth_term = false;  // fit Xu et al.'s c max(v.z, 0) exp(...) instead (comparison)
};

// visible[k] in {0, 1} for direction k. Safe for any input of matching sizes (K >= 1); the result
// is always finite and within the bounds above. With the default options it uses at most
// kAsgFitMaxEvaluations objective evaluations.
AsgFitResult fit_asg(const FitDirections& directions, const uint8_t* visible,
                     const AsgFitOptions& options = {});

// RMS error of lobe `params` against the samples.
double asg_rms_error(const FitDirections& directions, const uint8_t* visible,
                     const model::AsgParams<double>& params);

}  // namespace clothbake::raycast

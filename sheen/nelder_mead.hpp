// Nelder-Mead downhill simplex minimisation (Nelder and Mead 1965; the standard coefficients
// reflection 1, expansion 2, contraction 1/2, shrink 1/2, as in Lagarias et al. 1998).
// Derivative-free, deterministic; used to fit the LTC coefficients of one table entry.
#pragma once

#include <functional>
#include <vector>

namespace clothbake::sheen {

struct NelderMeadOptions {
  int max_evaluations = 2000;
  double f_tolerance = 1e-12;  // stop when max f - min f over the simplex is below this ...
  double x_tolerance = 1e-7;   // ... and every vertex is within this of the best (max norm)
};

struct NelderMeadResult {
  std::vector<double> x;
  double f = 0.0;
  int evaluations = 0;
  bool converged = false;
};

// Minimises f starting from x0 with an initial simplex of x0 and x0 + step[i] e_i.
// f may return +infinity to reject a point (e.g. outside a constraint).
NelderMeadResult nelder_mead(const std::function<double(const std::vector<double>&)>& f,
                             const std::vector<double>& x0, const std::vector<double>& step,
                             const NelderMeadOptions& options = {});

}  // namespace clothbake::sheen

#include "sheen/nelder_mead.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace clothbake::sheen {

NelderMeadResult nelder_mead(const std::function<double(const std::vector<double>&)>& f,
                             const std::vector<double>& x0, const std::vector<double>& step,
                             const NelderMeadOptions& options) {
  const std::size_t n = x0.size();
  if (n == 0 || step.size() != n)
    throw std::invalid_argument("nelder_mead: x0 and step must be non-empty and of equal size");

  NelderMeadResult result;
  auto eval = [&](const std::vector<double>& x) {
    ++result.evaluations;
    const double v = f(x);
    return std::isnan(v) ? std::numeric_limits<double>::infinity() : v;
  };

  std::vector<std::vector<double>> simplex(n + 1, x0);
  std::vector<double> values(n + 1);
  for (std::size_t i = 0; i < n; ++i)
    simplex[i + 1][i] += step[i];
  for (std::size_t i = 0; i <= n; ++i)
    values[i] = eval(simplex[i]);

  std::vector<std::size_t> order(n + 1);
  std::vector<double> centroid(n), trial(n), trial2(n);
  auto point = [&](double t, std::vector<double>& out, const std::vector<double>& worst) {
    // centroid + t * (centroid - worst)
    for (std::size_t k = 0; k < n; ++k)
      out[k] = centroid[k] + t * (centroid[k] - worst[k]);
  };

  while (true) {
    std::iota(order.begin(), order.end(), 0);
    // Stable order so that ties resolve the same way on every run.
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
    const std::size_t best = order.front(), worst = order.back(), second = order[n - 1];

    double spread = 0.0;
    for (std::size_t i = 0; i <= n; ++i)
      for (std::size_t k = 0; k < n; ++k)
        spread = std::max(spread, std::abs(simplex[i][k] - simplex[best][k]));
    if (values[worst] - values[best] <= options.f_tolerance && spread <= options.x_tolerance) {
      result.converged = true;
      break;
    }
    if (result.evaluations >= options.max_evaluations) break;

    std::fill(centroid.begin(), centroid.end(), 0.0);
    for (std::size_t i = 0; i <= n; ++i)
      if (i != worst)
        for (std::size_t k = 0; k < n; ++k)
          centroid[k] += simplex[i][k] / double(n);

    point(1.0, trial, simplex[worst]);  // reflection
    const double fr = eval(trial);
    if (fr < values[best]) {
      point(2.0, trial2, simplex[worst]);  // expansion
      const double fe = eval(trial2);
      if (fe < fr) {
        simplex[worst] = trial2;
        values[worst] = fe;
      } else {
        simplex[worst] = trial;
        values[worst] = fr;
      }
      continue;
    }
    if (fr < values[second]) {
      simplex[worst] = trial;
      values[worst] = fr;
      continue;
    }
    // Contraction: outside if the reflected point beats the worst, inside otherwise.
    const bool outside = fr < values[worst];
    point(outside ? 0.5 : -0.5, trial2, simplex[worst]);
    const double fc = eval(trial2);
    if (fc < (outside ? fr : values[worst])) {
      simplex[worst] = trial2;
      values[worst] = fc;
      continue;
    }
    // Shrink towards the best vertex.
    for (std::size_t i = 0; i <= n; ++i) {
      if (i == best) continue;
      for (std::size_t k = 0; k < n; ++k)
        simplex[i][k] = simplex[best][k] + 0.5 * (simplex[i][k] - simplex[best][k]);
      values[i] = eval(simplex[i]);
    }
  }

  const std::size_t best =
      std::size_t(std::min_element(values.begin(), values.end()) - values.begin());
  result.x = simplex[best];
  result.f = values[best];
  return result;
}

}  // namespace clothbake::sheen

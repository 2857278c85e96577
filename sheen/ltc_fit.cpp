#include "sheen/ltc_fit.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "sheen/nelder_mead.hpp"

namespace clothbake::sheen {
namespace {

// Gauss-Legendre nodes and weights on [-1, 1].
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  switch (n) {
    case 1:
      x = {0.0};
      w = {2.0};
      break;
    case 2:
      x = {-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)};
      w = {1.0, 1.0};
      break;
    case 3:
      x = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
      w = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
      break;
    case 4: {
      const double p = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(1.2));
      const double q = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(1.2));
      const double wp = (18.0 + std::sqrt(30.0)) / 36.0, wq = (18.0 - std::sqrt(30.0)) / 36.0;
      x = {-q, -p, p, q};
      w = {wq, wp, wp, wq};
      break;
    }
    default:
      throw std::invalid_argument("LtcBinQuadrature: nodes_per_axis must be 1 to 4");
  }
}

}  // namespace

LtcBinQuadrature::LtcBinQuadrature(const ExitBinning& binning, int nodes_per_axis)
    : binning_(binning), nodes_per_bin_(nodes_per_axis * nodes_per_axis) {
  std::vector<double> gx, gw;
  gauss_legendre(nodes_per_axis, gx, gw);
  solid_angle_.assign(binning.bin_count(), 0.0);
  const double dphi = kPi / binning.phi_bins;
  for (int iz = 0; iz < binning.z_bins; ++iz) {
    const double z0 = binning.z_edge(iz), z1 = binning.z_edge(iz + 1);
    for (int ip = 0; ip < binning.phi_bins; ++ip) {
      const int bin = iz * binning.phi_bins + ip;
      solid_angle_[bin] = 2.0 * (z1 - z0) * dphi;
      for (int a = 0; a < nodes_per_axis; ++a)
        for (int c = 0; c < nodes_per_axis; ++c) {
          const double z = 0.5 * (z0 + z1) + 0.5 * (z1 - z0) * gx[a];
          const double phi = (ip + 0.5) * dphi + 0.5 * dphi * gx[c];
          const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
          x_.push_back(s * std::cos(phi));
          y_.push_back(s * std::sin(phi));
          z_.push_back(z);
          // dOmega = dz dphi; x2 for the mirrored half (the lobe is symmetric in y).
          weight_.push_back(2.0 * 0.25 * (z1 - z0) * dphi * gw[a] * gw[c]);
        }
    }
  }
}

void LtcBinQuadrature::bin_probabilities(double a, double b, std::vector<double>& out) const {
  out.assign(binning_.bin_count(), 0.0);
  // model::sheen_ltc_density: D(w) = a^2 z / (pi |M^-1 w|^4), |M^-1 w|^2 = (a x + b z)^2 +
  // (a y)^2 + z^2, for w in the frame of wo.
  const double scale = a * a / kPi;
  const double* x = x_.data();
  const double* y = y_.data();
  const double* z = z_.data();
  const double* w = weight_.data();
  const std::size_t q = std::size_t(nodes_per_bin_);
  for (std::size_t bin = 0; bin < out.size(); ++bin) {
    double sum = 0.0;
    for (std::size_t k = bin * q; k < (bin + 1) * q; ++k) {
      const double tx = a * x[k] + b * z[k], ty = a * y[k];
      const double len2 = tx * tx + ty * ty + z[k] * z[k];
      sum += w[k] * z[k] / (len2 * len2);
    }
    out[bin] = scale * sum;
  }
}

LtcFit fit_ltc_lobe(const std::vector<double>& target, const LtcBinQuadrature& quadrature,
                    const std::vector<std::array<double, 2>>& starts, bool fix_b_zero) {
  const std::vector<double>& omega = quadrature.bin_solid_angles();
  if (target.size() != omega.size())
    throw std::invalid_argument("fit_ltc_lobe: target has the wrong number of bins");
  if (starts.empty()) throw std::invalid_argument("fit_ltc_lobe: no starting point");

  std::vector<double> probabilities;
  auto objective_of = [&](double a, double b) {
    if (!(a > 1e-6 && a < 1e6) || !(std::abs(b) < 1e6))
      return std::numeric_limits<double>::infinity();
    quadrature.bin_probabilities(a, b, probabilities);
    double e = 0.0;
    for (std::size_t k = 0; k < target.size(); ++k) {
      const double d = target[k] - probabilities[k];
      e += d * d / omega[k];
    }
    return e;
  };

  LtcFit best;
  best.objective = std::numeric_limits<double>::infinity();
  int evaluations = 0;

  // Coarse grid over (log a, b) first: the L2 objective is flat where the lobes do not overlap,
  // so a local search from a poor start can stall (e.g. a narrow grazing lobe started from the
  // cosine). The best grid point becomes one more start.
  std::vector<std::array<double, 2>> all_starts = starts;
  {
    double grid_best = std::numeric_limits<double>::infinity();
    std::array<double, 2> grid_start{1.0, 0.0};
    constexpr int kLogASteps = 16, kBSteps = 11;
    const double log_a_lo = std::log(0.004), log_a_hi = std::log(1.5);
    for (int ia = 0; ia < kLogASteps; ++ia) {
      const double a = std::exp(log_a_lo + (log_a_hi - log_a_lo) * ia / (kLogASteps - 1));
      for (int ib = 0; ib < (fix_b_zero ? 1 : kBSteps); ++ib) {
        const double b = fix_b_zero ? 0.0 : -0.5 + 1.0 * ib / (kBSteps - 1);
        const double e = objective_of(a, b);
        ++evaluations;
        if (e < grid_best) {
          grid_best = e;
          grid_start = {a, b};
        }
      }
    }
    all_starts.push_back(grid_start);
  }
  NelderMeadOptions options;
  options.max_evaluations = 1500;
  options.f_tolerance = 1e-14;
  options.x_tolerance = 1e-6;
  for (const auto& start : all_starts) {
    if (!(start[0] > 0.0)) throw std::invalid_argument("fit_ltc_lobe: a start has a <= 0");
    NelderMeadResult r;
    if (fix_b_zero) {
      r = nelder_mead(
          [&](const std::vector<double>& x) { return objective_of(std::exp(x[0]), 0.0); },
          {std::log(start[0])}, {0.2}, options);
      r.x.push_back(0.0);
    } else {
      r = nelder_mead(
          [&](const std::vector<double>& x) { return objective_of(std::exp(x[0]), x[1]); },
          {std::log(start[0]), start[1]}, {0.2, 0.1}, options);
    }
    evaluations += r.evaluations;
    if (r.f < best.objective) {
      best.a = std::exp(r.x[0]);
      best.b = r.x[1];
      best.objective = r.f;
    }
  }
  best.evaluations = evaluations;
  quadrature.bin_probabilities(best.a, best.b, probabilities);
  best.l1_error = 0.0;
  for (std::size_t k = 0; k < target.size(); ++k)
    best.l1_error += std::abs(target[k] - probabilities[k]);
  return best;
}

double expected_noise_l1(const std::vector<double>& target, uint64_t reflected_paths) {
  if (reflected_paths == 0) return 0.0;
  double sum = 0.0;
  for (double p : target)
    sum += std::sqrt(2.0 * std::max(0.0, p * (1.0 - p)) / (kPi * double(reflected_paths)));
  return sum;
}

}  // namespace clothbake::sheen

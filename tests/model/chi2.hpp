// The one statistical harness of the model tests: sphere quadrature (adaptive Simpson) and a
// chi-square goodness-of-fit test of a direction sampler against its claimed density, after
// pbrt-v4's and Mitsuba 3's BSDF tests (Pharr, Jakob, Humphreys; Jakob et al.): samples are
// histogrammed on an equal-area grid of the sphere (z uniform x phi uniform, Archimedes), the
// expected count of each cell is N times the density integrated over the cell by nested adaptive
// Simpson quadrature, cells expecting fewer than 5 samples are pooled, and the statistic's p-value
// (regularised upper incomplete gamma) is compared with a Sidak-corrected significance level.
//
// Samplers may fail (return false): the harness then compares the number of failures with the
// probability mass the density leaves off the sphere (e.g. the discrete delta lobe) as one more
// cell. Sampling runs in a fixed number of chunks with independent seeds, spread over threads, so
// the histogram does not depend on the thread count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "model/vec.hpp"

namespace clothbake::test {

using model::Vec3d;

// ---------------------------------------------------------------------------------------------
// Quadrature

// Adaptive Simpson on [a, b] to absolute tolerance tol, at most max_depth halvings.
template <class F>
double adaptive_simpson(const F& f, double a, double b, double tol, int max_depth = 14) {
  struct Rec {
    static double run(const F& f, double a, double b, double fa, double fm, double fb, double whole,
                      double tol, int depth) {
      const double m = 0.5 * (a + b);
      const double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
      const double flm = f(lm), frm = f(rm);
      const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
      const double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
      const double delta = left + right - whole;
      if (depth <= 0 || std::abs(delta) <= 15.0 * tol) return left + right + delta / 15.0;
      return run(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1) +
             run(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1);
    }
  };
  const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  const double whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
  return Rec::run(f, a, b, fa, fm, fb, whole, tol, max_depth);
}

// Adaptive Simpson after splitting [a, b] into `pieces` equal intervals (so that narrow features
// are not missed by the first, coarse estimate).
template <class F>
double composite_adaptive_simpson(const F& f, double a, double b, int pieces, double tol,
                                  int max_depth = 14) {
  double sum = 0.0;
  const double h = (b - a) / pieces;
  for (int k = 0; k < pieces; ++k)
    sum += adaptive_simpson(f, a + k * h, a + (k + 1) * h, tol / pieces, max_depth);
  return sum;
}

// An orthonormal frame: direction(z, phi) = e1 sqrt(1-z^2) cos phi + e2 sqrt(1-z^2) sin phi + n z.
struct SphereFrame {
  Vec3d e1{1, 0, 0}, e2{0, 1, 0}, n{0, 0, 1};
  Vec3d direction(double z, double phi) const {
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return e1 * (s * std::cos(phi)) + e2 * (s * std::sin(phi)) + n * z;
  }
  void coordinates(const Vec3d& w, double& z, double& phi) const {
    z = std::clamp(model::dot(w, n), -1.0, 1.0);
    phi = std::atan2(model::dot(w, e2), model::dot(w, e1));
    if (phi < 0) phi += 2 * M_PI;
  }
  static SphereFrame around(const Vec3d& pole) {
    SphereFrame f;
    f.n = model::normalize(pole);
    model::orthonormal_basis(f.n, f.e1, f.e2);
    return f;
  }
};

// Integral of f over the solid-angle cell z in [z0, z1], phi in [phi0, phi1] (dw = dz dphi).
template <class F>
double integrate_cell(const F& f, const SphereFrame& frame, double z0, double z1, double phi0,
                      double phi1, double tol, int max_depth = 10) {
  auto inner = [&](double z) {
    auto g = [&](double phi) { return f(frame.direction(z, phi)); };
    return adaptive_simpson(g, phi0, phi1, tol / (z1 - z0), max_depth);
  };
  return adaptive_simpson(inner, z0, z1, tol, max_depth);
}

// Integral of f over the whole sphere on a z_bins x phi_bins grid of cells (tol per cell).
template <class F>
double integrate_sphere(const F& f, const SphereFrame& frame, int z_bins, int phi_bins,
                        double tol_per_cell, int max_depth = 10) {
  double sum = 0.0;
  for (int i = 0; i < z_bins; ++i)
    for (int j = 0; j < phi_bins; ++j)
      sum += integrate_cell(f, frame, -1.0 + 2.0 * i / z_bins, -1.0 + 2.0 * (i + 1) / z_bins,
                            2 * M_PI * j / phi_bins, 2 * M_PI * (j + 1) / phi_bins, tol_per_cell,
                            max_depth);
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Statistics

// Regularised upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a), a > 0, x >= 0: the series
// of P below a + 1, Lentz's continued fraction for Q above.
inline double regularized_gamma_q(double a, double x) {
  if (x <= 0.0) return 1.0;
  const double log_prefix = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return std::max(0.0, 1.0 - sum * std::exp(log_prefix));
  }
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return std::exp(log_prefix) * h;
}

// p-value of a chi-square statistic with dof degrees of freedom.
inline double chi2_p_value(double statistic, int dof) {
  return regularized_gamma_q(0.5 * dof, 0.5 * statistic);
}

// Per-test significance level that keeps the family-wise level `alpha` over `tests` tests.
inline double sidak_level(double alpha, int tests) {
  return 1.0 - std::pow(1.0 - alpha, 1.0 / std::max(1, tests));
}

// ---------------------------------------------------------------------------------------------
// The chi-square test of a sampler

// Draws one direction from three uniform numbers in [0, 1); false = no direction (e.g. a delta).
using DirectionSampler = std::function<bool(double u0, double u1, double u2, Vec3d& out)>;
// Claimed solid-angle density of the sampler's directions (may integrate to less than 1).
using DirectionPdf = std::function<double(const Vec3d& w)>;

struct Chi2Options {
  int z_bins = 32;  // even, so that z = 0 is a cell border
  int phi_bins = 64;
  long long samples = 1000000;
  double min_expected = 5.0;     // cells expecting fewer samples are pooled
  double significance = 0.01;    // family-wise level
  int tests = 1;                 // number of tests in the family (Sidak correction)
  double cell_tolerance = 1e-8;  // absolute quadrature tolerance per cell, in probability
  std::uint64_t seed = 1;
  int chunks = 16;      // fixed: results do not depend on the thread count
  SphereFrame frame{};  // the histogram's pole and azimuth origin
};

struct Chi2Result {
  bool passed = false;
  double statistic = 0.0;
  int dof = 0;
  double p_value = 0.0;
  double level = 0.0;      // Sidak-corrected per-test significance level
  double pdf_mass = 0.0;   // integral of the density over the sphere
  long long failures = 0;  // samples for which the sampler returned false
  long long outside = 0;   // samples in cells of zero expected count (a hard failure)
  std::string message;     // summary, with the worst cells
};

inline Chi2Result chi2_test(const DirectionSampler& sampler, const DirectionPdf& pdf,
                            const Chi2Options& opt) {
  const int cells = opt.z_bins * opt.phi_bins;
  const unsigned threads = std::max(1u, std::min(4u, std::thread::hardware_concurrency()));

  // Histogram, in fixed chunks.
  std::vector<std::vector<long long>> chunk_hist(opt.chunks, std::vector<long long>(cells + 1, 0));
  auto run_chunks = [&](unsigned worker) {
    for (int c = int(worker); c < opt.chunks; c += int(threads)) {
      std::mt19937_64 rng(opt.seed * 0x9E3779B97F4A7C15ull + std::uint64_t(c) * 7919ull + 1ull);
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      const long long begin = opt.samples * c / opt.chunks,
                      end = opt.samples * (c + 1) / opt.chunks;
      std::vector<long long>& hist = chunk_hist[c];
      for (long long k = begin; k < end; ++k) {
        const double u0 = uni(rng), u1 = uni(rng), u2 = uni(rng);
        Vec3d w;
        if (!sampler(u0, u1, u2, w)) {
          ++hist[cells];
          continue;
        }
        double z, phi;
        opt.frame.coordinates(model::normalize(w), z, phi);
        const int i = std::clamp(int((z + 1.0) * 0.5 * opt.z_bins), 0, opt.z_bins - 1);
        const int j = std::clamp(int(phi / (2 * M_PI) * opt.phi_bins), 0, opt.phi_bins - 1);
        ++hist[i * opt.phi_bins + j];
      }
    }
  };
  // Expected mass per cell, in parallel over cells.
  std::vector<double> mass(cells, 0.0);
  auto run_cells = [&](unsigned worker) {
    for (int cell = int(worker); cell < cells; cell += int(threads)) {
      const int i = cell / opt.phi_bins, j = cell % opt.phi_bins;
      auto f = [&](const Vec3d& w) { return pdf(w); };
      mass[cell] = integrate_cell(f, opt.frame, -1.0 + 2.0 * i / opt.z_bins,
                                  -1.0 + 2.0 * (i + 1) / opt.z_bins, 2 * M_PI * j / opt.phi_bins,
                                  2 * M_PI * (j + 1) / opt.phi_bins, opt.cell_tolerance);
    }
  };
  {
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back(run_chunks, t);
    for (auto& t : pool)
      t.join();
    pool.clear();
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back(run_cells, t);
    for (auto& t : pool)
      t.join();
  }
  std::vector<long long> observed(cells + 1, 0);
  for (const auto& h : chunk_hist)
    for (int k = 0; k <= cells; ++k)
      observed[k] += h[k];

  Chi2Result result;
  result.level = sidak_level(opt.significance, opt.tests);
  result.failures = observed[cells];
  double total_mass = 0.0;
  for (double m : mass)
    total_mass += m;
  result.pdf_mass = total_mass;

  // Cells (plus the failure bucket) as (expected, observed), sorted by expected count.
  std::vector<std::pair<double, long long>> bins;
  const double n = double(opt.samples);
  std::ostringstream worst;
  for (int k = 0; k < cells; ++k) {
    const double expected = n * mass[k];
    if (!(expected > 0.0) && observed[k] > 0) result.outside += observed[k];
    bins.emplace_back(expected, observed[k]);
  }
  bins.emplace_back(std::max(0.0, n * (1.0 - total_mass)), observed[cells]);
  if (result.outside > 0) {
    std::ostringstream msg;
    msg << result.outside << " samples fell in cells where the density integrates to 0";
    result.message = msg.str();
    return result;
  }
  std::sort(bins.begin(), bins.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  // Pool the smallest cells (ascending) until the pool expects at least min_expected samples; every
  // cell below the threshold is in the pool, so each term of the statistic expects >= min_expected.
  double pooled_expected = 0.0;
  long long pooled_observed = 0;
  double chi2 = 0.0;
  int used = 0;
  double worst_term = 0.0;
  std::size_t k = 0;
  for (;
       k < bins.size() && (pooled_expected < opt.min_expected || bins[k].first < opt.min_expected);
       ++k) {
    pooled_expected += bins[k].first;
    pooled_observed += bins[k].second;
  }
  auto add_term = [&](double expected, long long obs) {
    if (!(expected > 0.0)) return;
    const double d = double(obs) - expected;
    const double term = d * d / expected;
    if (term > worst_term) {
      worst_term = term;
      worst.str("");
      worst << "worst cell: expected " << expected << ", observed " << obs;
    }
    chi2 += term;
    ++used;
  };
  add_term(pooled_expected, pooled_observed);
  for (; k < bins.size(); ++k)
    add_term(bins[k].first, bins[k].second);
  result.statistic = chi2;
  result.dof = std::max(1, used - 1);
  result.p_value = chi2_p_value(chi2, result.dof);
  result.passed = result.p_value >= result.level;
  std::ostringstream msg;
  msg << "chi2 = " << chi2 << ", dof = " << result.dof << ", p = " << result.p_value << " (level "
      << result.level << "), density mass " << total_mass << ", failures " << result.failures
      << ", pooled expected " << pooled_expected << " observed " << pooled_observed << "; "
      << worst.str();
  result.message = msg.str();
  return result;
}

}  // namespace clothbake::test

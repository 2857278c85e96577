// Test helpers of tests/sheen: quadrature over the sphere and a chi-square goodness-of-fit test of
// a direction sampler against its density (bins equal in solid angle, expected counts integrated
// over each bin, bins with expected count below 5 pooled, as in Mitsuba's chi2 tests).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "model/vec.hpp"

namespace clothbake::sheen_test {

using Vec3d = model::Vec3<double>;
inline constexpr double kPi = 3.14159265358979323846;

inline Vec3d direction_zphi(double z, double phi) {
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

// Midpoint rule over z in [z_lo, z_hi] and phi in [0, 2 pi): dOmega = dz dphi.
inline double integrate_zphi(const std::function<double(const Vec3d&)>& f, double z_lo, double z_hi,
                             int nz, int nphi) {
  double sum = 0.0;
  const double dz = (z_hi - z_lo) / nz, dphi = 2.0 * kPi / nphi;
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nphi; ++j)
      sum += f(direction_zphi(z_lo + (i + 0.5) * dz, (j + 0.5) * dphi));
  return sum * dz * dphi;
}

inline double integrate_sphere(const std::function<double(const Vec3d&)>& f, int nz, int nphi) {
  return integrate_zphi(f, -1.0, 1.0, nz, nphi);
}
inline double integrate_hemisphere(const std::function<double(const Vec3d&)>& f, int nz, int nphi) {
  return integrate_zphi(f, 0.0, 1.0, nz, nphi);
}

struct ChiSquareResult {
  bool passed = false;
  double chi2 = 0.0;
  int dof = 0;
  double z_score = 0.0;  // Wilson-Hilferty normal score of chi2
  std::string message;
};

// Draws `samples` directions and compares their histogram with the density integrated over each
// bin (sub x sub midpoint cells). Bins: nphi equal azimuths times nz bins of z = z_of_t(t) for t
// uniform in [0, 1] (z_of_t increasing; dz_dt its derivative). Fails at a significance of about
// 1e-6 (normal score above 4.75), and when the density does not integrate to 1 within 1e-3.
inline ChiSquareResult chi_square_mapped(const std::function<Vec3d()>& sample,
                                         const std::function<double(const Vec3d&)>& pdf,
                                         int samples, const std::function<double(double)>& z_of_t,
                                         const std::function<double(double)>& dz_dt,
                                         const std::function<double(double)>& t_of_z, int nz = 32,
                                         int nphi = 64, int sub = 6) {
  std::vector<double> observed(std::size_t(nz * nphi), 0.0), expected(observed.size(), 0.0);
  const double dt = 1.0 / nz, dphi = 2.0 * kPi / nphi;
  const double z_lo = z_of_t(0.0);
  int outside = 0;
  for (int k = 0; k < samples; ++k) {
    const Vec3d w = sample();
    if (!(w.z >= z_lo) || !std::isfinite(w.x) || !std::isfinite(w.y)) {
      ++outside;
      continue;
    }
    double phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2.0 * kPi;
    const int i = std::clamp(int(t_of_z(std::min(w.z, 1.0)) / dt), 0, nz - 1);
    const int j = std::clamp(int(phi / dphi), 0, nphi - 1);
    observed[std::size_t(i * nphi + j)] += 1.0;
  }
  double total_probability = 0.0;
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nphi; ++j) {
      double p = 0.0;
      for (int a = 0; a < sub; ++a) {
        const double t = (i + (a + 0.5) / sub) * dt;
        for (int b = 0; b < sub; ++b)
          p += pdf(direction_zphi(z_of_t(t), (j + (b + 0.5) / sub) * dphi)) * dz_dt(t);
      }
      p *= dt * dphi / (sub * sub);
      total_probability += p;
      expected[std::size_t(i * nphi + j)] = p * samples;
    }
  ChiSquareResult r;
  // Pool the bins with small expectations (in increasing order of expectation) into one.
  std::vector<std::size_t> order(observed.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    order[k] = k;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return expected[a] < expected[b]; });
  double pool_observed = outside, pool_expected = 0.0;
  int bins = 0;
  for (std::size_t k : order) {
    if (expected[k] < 5.0 || (pool_expected > 0.0 && pool_expected < 5.0)) {
      pool_observed += observed[k];
      pool_expected += expected[k];
      continue;
    }
    const double d = observed[k] - expected[k];
    r.chi2 += d * d / expected[k];
    ++bins;
  }
  if (pool_expected > 0.0) {
    const double d = pool_observed - pool_expected;
    r.chi2 += d * d / pool_expected;
    ++bins;
  } else if (pool_observed > 0.0) {
    r.chi2 = INFINITY;  // samples where the density says none can be
  }
  r.dof = std::max(1, bins - 1);
  const double k = r.dof;
  r.z_score = (std::cbrt(r.chi2 / k) - (1.0 - 2.0 / (9.0 * k))) / std::sqrt(2.0 / (9.0 * k));
  r.passed = r.z_score < 4.75 && std::abs(total_probability - 1.0) < 1e-3;
  r.message = "chi2 " + std::to_string(r.chi2) + " with " + std::to_string(r.dof) +
              " dof, normal score " + std::to_string(r.z_score) + ", density integral " +
              std::to_string(total_probability) + ", samples outside " + std::to_string(outside);
  return r;
}

// Whole sphere, bins uniform in z (equal solid angle).
inline ChiSquareResult chi_square_sphere(const std::function<Vec3d()>& sample,
                                         const std::function<double(const Vec3d&)>& pdf,
                                         int samples) {
  return chi_square_mapped(
      sample, pdf, samples, [](double t) { return 2.0 * t - 1.0; }, [](double) { return 2.0; },
      [](double z) { return 0.5 * (z + 1.0); });
}
// Upper hemisphere, z = t^2: bins and integration cells crowd towards the horizon, where sheen
// lobes are narrow.
inline ChiSquareResult chi_square_hemisphere(const std::function<Vec3d()>& sample,
                                             const std::function<double(const Vec3d&)>& pdf,
                                             int samples) {
  return chi_square_mapped(
      sample, pdf, samples, [](double t) { return t * t; }, [](double t) { return 2.0 * t; },
      [](double z) { return std::sqrt(std::max(z, 0.0)); });
}

// Integral over the upper hemisphere with z = t^2 (midpoint in t and phi): accurate for lobes
// concentrated at grazing angles.
inline double integrate_hemisphere_grazing(const std::function<double(const Vec3d&)>& f, int nt,
                                           int nphi) {
  double sum = 0.0;
  const double dt = 1.0 / nt, dphi = 2.0 * kPi / nphi;
  for (int i = 0; i < nt; ++i) {
    const double t = (i + 0.5) * dt;
    double ring = 0.0;
    for (int j = 0; j < nphi; ++j)
      ring += f(direction_zphi(t * t, (j + 0.5) * dphi));
    sum += ring * 2.0 * t;
  }
  return sum * dt * dphi;
}

}  // namespace clothbake::sheen_test

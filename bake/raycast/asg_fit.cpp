#include "bake/raycast/asg_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace clothbake::raycast {
namespace {

using model::kAsgMaxAmplitude;
using model::kAsgMaxBandwidth;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The lobe during the fit: frame columns x, y, z.
struct Lobe {
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  double lambda = 0, mu = 0, c = 0;
};

double objective(const FitDirections& d, const uint8_t* visible, const Lobe& lobe) {
  const Eigen::Vector3d ax = lobe.frame.col(0), ay = lobe.frame.col(1), az = lobe.frame.col(2);
  double sum = 0;
  const std::size_t k_count = d.size();
  for (std::size_t k = 0; k < k_count; ++k) {
    double vz = az.x() * d.x[k] + az.y() * d.y[k] + az.z() * d.z[k];
    double g = 0;
    if (vz > 0) {
      double vx = ax.x() * d.x[k] + ax.y() * d.y[k] + ax.z() * d.z[k];
      double vy = ay.x() * d.x[k] + ay.y() * d.y[k] + ay.z() * d.z[k];
      g = lobe.c * std::exp(-lobe.lambda * vx * vx - lobe.mu * vy * vy);
    }
    double r = g - double(visible[k]);
    sum += r * r;
  }
  return sum;
}

// Gauss-Newton normal equations at `lobe`. Parameters: rotation increment w (local frame, 3),
// lambda, mu, c. A frame rotated by R(w) sees direction v at v_local - w x v_local, so d(v.x)/dw =
// (0, -v.z, v.y) and d(v.y)/dw = (v.z, 0, -v.x).
void normal_equations(const FitDirections& d, const uint8_t* visible, const Lobe& lobe,
                      Matrix6& jtj, Vector6& jtr) {
  const Eigen::Vector3d ax = lobe.frame.col(0), ay = lobe.frame.col(1), az = lobe.frame.col(2);
  double a[21] = {};  // upper triangle, row-major
  double b[6] = {};
  const std::size_t k_count = d.size();
  for (std::size_t k = 0; k < k_count; ++k) {
    double vz = az.x() * d.x[k] + az.y() * d.y[k] + az.z() * d.z[k];
    if (!(vz > 0)) continue;  // G = 0 and its derivatives vanish (almost everywhere)
    double vx = ax.x() * d.x[k] + ax.y() * d.y[k] + ax.z() * d.z[k];
    double vy = ay.x() * d.x[k] + ay.y() * d.y[k] + ay.z() * d.z[k];
    double e = std::exp(-lobe.lambda * vx * vx - lobe.mu * vy * vy);
    double g = lobe.c * e;
    double r = g - double(visible[k]);
    double j[6] = {-2 * g * lobe.mu * vy * vz,
                   2 * g * lobe.lambda * vx * vz,
                   -2 * g * (lobe.lambda - lobe.mu) * vx * vy,
                   -g * vx * vx,
                   -g * vy * vy,
                   e};
    int idx = 0;
    for (int p = 0; p < 6; ++p) {
      b[p] += j[p] * r;
      for (int q = p; q < 6; ++q)
        a[idx++] += j[p] * j[q];
    }
  }
  int idx = 0;
  for (int p = 0; p < 6; ++p) {
    jtr(p) = b[p];
    for (int q = p; q < 6; ++q)
      jtj(p, q) = jtj(q, p) = a[idx++];
  }
}

Eigen::Matrix3d rotation(const Eigen::Vector3d& w) {
  double theta = w.norm();
  if (theta < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
}

// Re-orthonormalises the frame and keeps the axis in the upper hemisphere (z.z >= 0).
void project_frame(Eigen::Matrix3d& frame) {
  Eigen::Vector3d z = frame.col(2);
  if (z.z() < 0) z.z() = 0;
  if (z.norm() < 1e-12) z = Eigen::Vector3d::UnitZ();
  z.normalize();
  Eigen::Vector3d x = frame.col(0) - frame.col(0).dot(z) * z;
  if (x.norm() < 1e-9) x = z.unitOrthogonal();
  x.normalize();
  frame.col(0) = x;
  frame.col(1) = z.cross(x);
  frame.col(2) = z;
}

// The amplitude minimising the objective for the lobe's shape (linear least squares), clamped.
void set_best_amplitude(const FitDirections& d, const uint8_t* visible, Lobe& lobe) {
  const Eigen::Vector3d ax = lobe.frame.col(0), ay = lobe.frame.col(1), az = lobe.frame.col(2);
  double ev = 0, ee = 0;
  for (std::size_t k = 0; k < d.size(); ++k) {
    double vz = az.x() * d.x[k] + az.y() * d.y[k] + az.z() * d.z[k];
    if (!(vz > 0)) continue;
    double vx = ax.x() * d.x[k] + ax.y() * d.y[k] + ax.z() * d.z[k];
    double vy = ay.x() * d.x[k] + ay.y() * d.y[k] + ay.z() * d.z[k];
    double e = std::exp(-lobe.lambda * vx * vx - lobe.mu * vy * vy);
    ev += e * double(visible[k]);
    ee += e * e;
  }
  lobe.c = ee > 0 ? std::clamp(ev / ee, 0.0, kAsgMaxAmplitude) : 0.0;
}

model::AsgParams<double> to_params(const Lobe& lobe) {
  model::Asg<double> g;
  g.x = {lobe.frame(0, 0), lobe.frame(1, 0), lobe.frame(2, 0)};
  g.y = {lobe.frame(0, 1), lobe.frame(1, 1), lobe.frame(2, 1)};
  g.z = {lobe.frame(0, 2), lobe.frame(1, 2), lobe.frame(2, 2)};
  g.lambda = lobe.lambda;
  g.mu = lobe.mu;
  g.amplitude = lobe.c;
  return model::asg_to_params(g);
}

// Start from the moments of the visible directions: axis = their mean, the principal axes of their
// spread about it give x (smaller spread: sharper) and y, and a bandwidth ~ 1 / (3 variance) - 1
// (the Gaussian that best matches a band of that variance, zero for a full hemisphere).
Lobe moment_start(const FitDirections& d, const uint8_t* visible) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double count = 0;
  for (std::size_t k = 0; k < d.size(); ++k)
    if (visible[k]) {
      mean += Eigen::Vector3d(d.x[k], d.y[k], d.z[k]);
      count += 1;
    }
  Lobe lobe;
  Eigen::Vector3d z =
      mean.norm() > 1e-9 ? Eigen::Vector3d(mean.normalized()) : Eigen::Vector3d::UnitZ();
  model::Vec3d s, t;
  model::orthonormal_basis(model::Vec3d{z.x(), z.y(), z.z()}, s, t);
  Eigen::Vector3d e1(s.x, s.y, s.z), e2(t.x, t.y, t.z);
  double c11 = 0, c12 = 0, c22 = 0;
  for (std::size_t k = 0; k < d.size(); ++k)
    if (visible[k]) {
      Eigen::Vector3d v(d.x[k], d.y[k], d.z[k]);
      double p = v.dot(e1), q = v.dot(e2);
      c11 += p * p;
      c12 += p * q;
      c22 += q * q;
    }
  c11 /= count;
  c12 /= count;
  c22 /= count;
  // Eigen-decomposition of the 2 x 2 covariance: angle of the larger-spread axis.
  double angle = 0.5 * std::atan2(2 * c12, c11 - c22);
  double mid = 0.5 * (c11 + c22), half = std::sqrt(0.25 * (c11 - c22) * (c11 - c22) + c12 * c12);
  double var_wide = mid + half, var_narrow = std::max(mid - half, 0.0);
  Eigen::Vector3d wide = std::cos(angle) * e1 + std::sin(angle) * e2;
  Eigen::Vector3d narrow = z.cross(wide);
  auto bandwidth = [](double var) {
    if (!(var > 1e-12)) return kAsgMaxBandwidth;
    return std::clamp(1.0 / (3.0 * var) - 1.0, 0.0, kAsgMaxBandwidth);
  };
  lobe.frame.col(0) = narrow;
  lobe.frame.col(1) = z.cross(narrow);
  lobe.frame.col(2) = z;
  lobe.lambda = bandwidth(var_narrow);
  lobe.mu = bandwidth(var_wide);
  project_frame(lobe.frame);
  set_best_amplitude(d, visible, lobe);
  return lobe;
}

// A zero-bandwidth lobe is the half-space above a plane: exactly the sky of a texel on a tilted
// facet. Its axis cannot be found by gradients (moving the cut plane changes the objective only
// where samples cross it), so the tilt is searched directly: axes in the vertical plane through the
// mean visible direction, tilted by beta in [0, pi/2] from the zenith, golden-section search on the
// objective with the best amplitude (closed form: E = sum V - (sum_in V)^2 / count_in).
Lobe half_space_start(const FitDirections& d, const uint8_t* visible, int* evaluations) {
  Eigen::Vector2d azimuth = Eigen::Vector2d::Zero();
  double total = 0;
  for (std::size_t k = 0; k < d.size(); ++k)
    if (visible[k]) {
      azimuth += Eigen::Vector2d(d.x[k], d.y[k]);
      total += 1;
    }
  Eigen::Vector2d h =
      azimuth.norm() > 1e-9 ? Eigen::Vector2d(azimuth.normalized()) : Eigen::Vector2d(1, 0);
  auto energy = [&](double beta, double* amplitude) {
    const double ax = std::sin(beta) * h.x(), ay = std::sin(beta) * h.y(), az = std::cos(beta);
    double inside = 0, seen_inside = 0;
    for (std::size_t k = 0; k < d.size(); ++k)
      if (ax * d.x[k] + ay * d.y[k] + az * d.z[k] > 0) {
        inside += 1;
        seen_inside += visible[k];
      }
    ++*evaluations;
    double c = inside > 0 ? std::min(seen_inside / inside, kAsgMaxAmplitude) : 0.0;
    if (amplitude) *amplitude = c;
    return total - 2 * c * seen_inside + c * c * inside;
  };
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = 0, hi = 0.5 * model::kPi<double>;
  double b1 = hi - golden * (hi - lo), b2 = lo + golden * (hi - lo);
  double e1 = energy(b1, nullptr), e2 = energy(b2, nullptr);
  for (int it = 0; it < 10; ++it) {
    if (e1 <= e2) {
      hi = b2, b2 = b1, e2 = e1;
      b1 = hi - golden * (hi - lo);
      e1 = energy(b1, nullptr);
    } else {
      lo = b1, b1 = b2, e1 = e2;
      b2 = lo + golden * (hi - lo);
      e2 = energy(b2, nullptr);
    }
  }
  Lobe lobe;
  double beta = e1 <= e2 ? b1 : b2;
  // The flat lobe about +z (beta = 0) is always a candidate: the search may miss the end point.
  if (energy(0.0, nullptr) <= std::min(e1, e2)) beta = 0.0;
  Eigen::Vector3d z(std::sin(beta) * h.x(), std::sin(beta) * h.y(), std::cos(beta));
  lobe.frame.col(2) = z;
  lobe.frame.col(0) = z.unitOrthogonal();
  project_frame(lobe.frame);
  energy(beta, &lobe.c);
  return lobe;
}

}  // namespace

double asg_rms_error(const FitDirections& directions, const uint8_t* visible,
                     const model::AsgParams<double>& params) {
  if (directions.size() == 0) return 0.0;
  model::Asg<double> g = model::asg_from_params(params);
  Lobe lobe;
  lobe.frame << g.x.x, g.y.x, g.z.x, g.x.y, g.y.y, g.z.y, g.x.z, g.y.z, g.z.z;
  lobe.lambda = g.lambda;
  lobe.mu = g.mu;
  lobe.c = g.amplitude;
  return std::sqrt(objective(directions, visible, lobe) / double(directions.size()));
}

AsgFitResult fit_asg(const FitDirections& d, const uint8_t* visible) {
  AsgFitResult result;
  const std::size_t k_count = d.size();
  if (k_count == 0) return result;
  std::size_t seen = 0;
  for (std::size_t k = 0; k < k_count; ++k)
    seen += visible[k] ? 1 : 0;
  if (seen == 0 || seen == k_count) {
    // V = 0 or V = 1 on every sample: represented exactly by a flat lobe about +z.
    result.params.amplitude = seen == 0 ? 0.0 : 1.0;
    return result;
  }

  // Starts: the moments of the visible directions, and the best half-space (which includes the
  // flat lobe about +z, beta = 0); the better one is refined.
  int evaluations = 0;
  Lobe lobe = moment_start(d, visible);
  double energy = objective(d, visible, lobe);
  Lobe half = half_space_start(d, visible, &evaluations);
  double half_energy = objective(d, visible, half);
  evaluations += 2;
  if (half_energy < energy) {
    lobe = half;
    energy = half_energy;
  }

  double damping = 1e-3;
  Matrix6 jtj;
  Vector6 jtr;
  bool fresh = false;  // normal equations up to date for `lobe`
  const int budget = evaluations + kAsgFitMaxRefinements;
  while (evaluations < budget) {
    if (!fresh) {
      normal_equations(d, visible, lobe, jtj, jtr);
      fresh = true;
    }
    Matrix6 a = jtj;
    for (int p = 0; p < 6; ++p)
      a(p, p) += damping * jtj(p, p) + 1e-12;
    Vector6 step = a.ldlt().solve(-jtr);
    if (!step.allFinite()) break;
    Lobe trial = lobe;
    trial.frame = lobe.frame * rotation(step.head<3>());
    project_frame(trial.frame);
    trial.lambda = std::clamp(lobe.lambda + step(3), 0.0, kAsgMaxBandwidth);
    trial.mu = std::clamp(lobe.mu + step(4), 0.0, kAsgMaxBandwidth);
    trial.c = std::clamp(lobe.c + step(5), 0.0, kAsgMaxAmplitude);
    double trial_energy = objective(d, visible, trial);
    ++evaluations;
    if (trial_energy < energy) {
      double gain = energy - trial_energy;
      lobe = trial;
      energy = trial_energy;
      fresh = false;
      damping = std::max(damping / 3, 1e-9);
      if (gain < 1e-9 * double(k_count)) break;  // converged: RMS changes below ~3e-5
    } else {
      damping *= 4;
      if (damping > 1e8) break;
    }
  }
  result.params = to_params(lobe);
  result.rms_error = std::sqrt(energy / double(k_count));
  result.evaluations = evaluations;
  return result;
}

}  // namespace clothbake::raycast

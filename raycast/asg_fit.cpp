#include "raycast/asg_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "model/splitmix64.hpp"

namespace clothbake::raycast {
namespace {

using model::kAsgMaxAmplitude;
using model::kAsgMaxBandwidth;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using ArrayF = Eigen::ArrayXf;
using MapF = Eigen::Map<const Eigen::ArrayXf>;

// The lobe during the fit: frame columns x, y, z.
struct Lobe {
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  double lambda = 0, mu = 0, c = 0;
};

// The samples of one fit as Eigen arrays, and the per-sample work arrays of the last lobe
// evaluated (so that an accepted trial step's normal equations reuse its exponentials). Every
// per-sample pass is an Eigen array expression: vectorised, including the exponential.
class Problem {
 public:
  Problem(const FitDirections& d, const uint8_t* visible, bool smooth_term = false)
      : smooth_(smooth_term),
        x_(d.x.data(), Eigen::Index(d.size())),
        y_(d.y.data(), Eigen::Index(d.size())),
        z_(d.z.data(), Eigen::Index(d.size())),
        v_(Eigen::Index(d.size())) {
    for (std::size_t k = 0; k < d.size(); ++k)
      v_[Eigen::Index(k)] = visible[k] ? 1.f : 0.f;
  }
  Eigen::Index size() const { return v_.size(); }
  const MapF& x() const { return x_; }
  const MapF& y() const { return y_; }
  const MapF& z() const { return z_; }
  const ArrayF& v() const { return v_; }

  // 1 where a >= 2^-100, 0 where a <= 0 (and a * 2^100 in between, which unit vectors never
  // produce except exactly on a lobe's cut plane), written with min/max so that Eigen vectorises
  // it: a comparison-select falls back to scalar code and drags the exponential with it.
  template <class Expr>
  static auto positive(const Expr& a) {
    constexpr float kTiny = 0x1p-100f, kHuge = 0x1p100f;
    return a.max(0.f).min(kTiny) * kHuge;
  }

  // Sum of squared residuals of `lobe`; leaves its per-sample arrays in the workspace.
  double energy(const Lobe& lobe) {
    project(lobe.frame.col(0), vx_);
    project(lobe.frame.col(1), vy_);
    project(lobe.frame.col(2), vz_);
    const float lambda = float(lobe.lambda), mu = float(lobe.mu);
    ex_ = (-(lambda * vx_.square() + mu * vy_.square())).exp() * positive(vz_);
    if (smooth_)
      e_ = ex_ * vz_.max(0.f);  // Xu et al.'s smooth term (studies only, see AsgFitOptions)
    else
      e_ = ex_;
    r_ = float(lobe.c) * e_ - v_;
    return double(r_.matrix().squaredNorm());
  }

  // Gauss-Newton normal equations at the lobe of the last energy() call. Parameters: rotation
  // increment w of the frame (local coordinates, 3), lambda, mu, c. A frame rotated by R(w) sees
  // direction v at v_local - w x v_local, so d(v.x)/dw = (0, -v.z, v.y) and d(v.y)/dw = (v.z, 0,
  // -v.x); samples behind the axis (G = 0) have zero rows.
  void normal_equations(const Lobe& lobe, Matrix6& jtj, Vector6& jtr) {
    const float lambda = float(lobe.lambda), mu = float(lobe.mu), c = float(lobe.c);
    jac_.resize(size(), 6);
    ArrayF g = c * e_;
    jac_.col(0) = (-2.f * mu * g * vy_ * vz_).matrix();
    jac_.col(1) = (2.f * lambda * g * vx_ * vz_).matrix();
    jac_.col(2) = (-2.f * (lambda - mu) * g * vx_ * vy_).matrix();
    jac_.col(3) = (-g * vx_.square()).matrix();
    jac_.col(4) = (-g * vy_.square()).matrix();
    jac_.col(5) = e_.matrix();
    if (smooth_) {  // G = c ex v.z: plus c ex d(v.z)/dw, d(v.z)/dw = (-v.y, v.x, 0)
      jac_.col(0) += (-c * ex_ * vy_).matrix();
      jac_.col(1) += (c * ex_ * vx_).matrix();
    }
    jtj = (jac_.transpose() * jac_).cast<double>();
    jtr = (jac_.transpose() * r_.matrix()).cast<double>();
  }

  // Sums of e * V and e^2 for the last energy() call (the best amplitude is their ratio).
  // Changes the amplitude of the last energy() call's lobe to c without recomputing the
  // exponentials; returns the new energy (the workspace then holds the lobe with amplitude c).
  double set_amplitude(double c) {
    r_ = float(c) * e_ - v_;
    return double(r_.matrix().squaredNorm());
  }

  void amplitude_sums(double& ev, double& ee) const {
    ev = double((e_ * v_).sum());
    ee = double(e_.square().sum());
  }

 private:
  void project(const Eigen::Vector3d& axis, ArrayF& out) const {
    out = float(axis.x()) * x_ + float(axis.y()) * y_ + float(axis.z()) * z_;
  }

  bool smooth_ = false;
  MapF x_, y_, z_;
  ArrayF v_;
  ArrayF vx_, vy_, vz_, ex_, e_, r_;
  Eigen::Matrix<float, Eigen::Dynamic, 6> jac_;
};

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
// Returns the energy; the workspace holds the lobe afterwards.
double set_best_amplitude(Problem& problem, Lobe& lobe) {
  problem.energy(lobe);
  double ev, ee;
  problem.amplitude_sums(ev, ee);
  lobe.c = ee > 0 ? std::clamp(ev / ee, 0.0, kAsgMaxAmplitude) : 0.0;
  return problem.set_amplitude(lobe.c);
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
Lobe moment_start(Problem& problem, double* energy) {
  const ArrayF& v = problem.v();
  const double count = double(v.sum());
  Eigen::Vector3d mean(double((v * problem.x()).sum()), double((v * problem.y()).sum()),
                       double((v * problem.z()).sum()));
  Lobe lobe;
  Eigen::Vector3d z =
      mean.norm() > 1e-9 ? Eigen::Vector3d(mean.normalized()) : Eigen::Vector3d::UnitZ();
  model::Vec3d s, t;
  model::orthonormal_basis(model::Vec3d{z.x(), z.y(), z.z()}, s, t);
  Eigen::Vector3d e1(s.x, s.y, s.z), e2(t.x, t.y, t.z);
  const ArrayF p =
      float(e1.x()) * problem.x() + float(e1.y()) * problem.y() + float(e1.z()) * problem.z();
  const ArrayF q =
      float(e2.x()) * problem.x() + float(e2.y()) * problem.y() + float(e2.z()) * problem.z();
  const double c11 = double((v * p.square()).sum()) / count;
  const double c12 = double((v * p * q).sum()) / count;
  const double c22 = double((v * q.square()).sum()) / count;
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
  *energy = set_best_amplitude(problem, lobe);
  return lobe;
}

// A zero-bandwidth lobe is the half-space above a plane: exactly the sky of a texel on a tilted
// facet. Its axis cannot be found by gradients (moving the cut plane changes the objective only
// where samples cross it), so the tilt is searched directly: axes in the vertical plane through the
// mean visible direction, tilted by beta in [0, pi/2] from the zenith, golden-section search on the
// objective with the best amplitude (closed form: E = sum V - (sum_in V)^2 / count_in).
Lobe half_space_start(Problem& problem, int* evaluations) {
  const ArrayF& v = problem.v();
  const double total = double(v.sum());
  Eigen::Vector2d azimuth(double((v * problem.x()).sum()), double((v * problem.y()).sum()));
  Eigen::Vector2d h =
      azimuth.norm() > 1e-9 ? Eigen::Vector2d(azimuth.normalized()) : Eigen::Vector2d(1, 0);
  auto energy = [&](double beta, double* amplitude) {
    const float ax = float(std::sin(beta) * h.x()), ay = float(std::sin(beta) * h.y()),
                az = float(std::cos(beta));
    const ArrayF in = Problem::positive(ax * problem.x() + ay * problem.y() + az * problem.z());
    const double inside = double(in.sum()), seen_inside = double((in * v).sum());
    ++*evaluations;
    double c = inside > 0 ? std::min(seen_inside / inside, kAsgMaxAmplitude) : 0.0;
    if (amplitude) *amplitude = c;
    return total - 2 * c * seen_inside + c * c * inside;
  };
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = 0, hi = 0.5 * model::kPi<double>;
  double b1 = hi - golden * (hi - lo), b2 = lo + golden * (hi - lo);
  double e1 = energy(b1, nullptr), e2 = energy(b2, nullptr);
  for (int it = 0; it < 10; ++it) {  // bracket (pi/2) 0.618^10 = 0.013 rad
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
  Problem problem(directions, visible);
  return std::sqrt(problem.energy(lobe) / double(directions.size()));
}

namespace {

// Levenberg-Marquardt from `lobe` (energy `energy`; the problem's workspace must hold `lobe`) with
// at most `refinements` trial steps. Returns the refined lobe and energy.
void refine(Problem& problem, Lobe& lobe, double& energy, int refinements, int& evaluations) {
  double damping = 1e-3;
  Matrix6 jtj;
  Vector6 jtr;
  bool fresh = false;  // normal equations up to date for `lobe`
  const int budget = evaluations + refinements;
  while (evaluations < budget) {
    if (!fresh) {
      problem.normal_equations(lobe, jtj, jtr);  // the workspace holds `lobe` (see below)
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
    double trial_energy = problem.energy(trial);
    ++evaluations;
    if (trial_energy < energy) {  // accepted: the workspace now holds `lobe`
      double gain = energy - trial_energy;
      lobe = trial;
      energy = trial_energy;
      fresh = false;
      damping = std::max(damping / 3, 1e-9);
      if (gain < 1e-4 * energy) break;  // converged: the RMS error changes by < 0.005 %
    } else {
      // Rejected: the workspace holds the trial, but the normal equations stay those of `lobe`
      // (`fresh`), and they are only recomputed after an acceptance, when it holds `lobe` again.
      damping *= 4;
      if (damping > 1e8) break;
    }
  }
}

// A deterministic random lobe (splitmix64): axis uniform on the hemisphere, log-uniform
// bandwidths in [0.1, 1000], best amplitude.
Lobe random_start(Problem& problem, uint64_t& state) {
  auto next = [&state] { return double(model::splitmix64_next(state) >> 11) * 0x1p-53; };
  double cz = next(), phi = 2 * model::kPi<double> * next(), sz = std::sqrt(1 - cz * cz);
  Lobe lobe;
  Eigen::Vector3d z(sz * std::cos(phi), sz * std::sin(phi), cz);
  lobe.frame.col(2) = z;
  lobe.frame.col(0) = z.unitOrthogonal();
  lobe.frame = lobe.frame * rotation(z * (2 * model::kPi<double> * next()));
  project_frame(lobe.frame);
  lobe.lambda = std::pow(10.0, -1 + 4 * next());
  lobe.mu = std::pow(10.0, -1 + 4 * next());
  set_best_amplitude(problem, lobe);
  return lobe;
}

}  // namespace

AsgFitResult fit_asg(const FitDirections& d, const uint8_t* visible, const AsgFitOptions& options) {
  AsgFitResult result;
  const std::size_t k_count = d.size();
  if (k_count == 0) return result;
  std::size_t seen = 0;
  for (std::size_t k = 0; k < k_count; ++k)
    seen += visible[k] ? 1 : 0;
  if ((seen == 0 || seen == k_count) && !options.xu_smooth_term) {
    // V = 0 or V = 1 on every sample: represented exactly by a flat lobe about +z.
    result.params.amplitude = seen == 0 ? 0.0 : 1.0;
    return result;
  }

  // Starts: the moments of the visible directions, and the best half-space (which includes the
  // flat lobe about +z, beta = 0); the better one is refined.
  Problem problem(d, visible, options.xu_smooth_term);
  int evaluations = 0;
  Lobe half = half_space_start(problem, &evaluations);
  const double half_energy = problem.energy(half);
  double energy = 0;
  Lobe lobe = moment_start(problem, &energy);  // the workspace now holds the moment start
  evaluations += 2;
  if (half_energy < energy) {
    lobe = half;
    energy = problem.energy(half);  // the workspace must hold the start being refined
  }
  refine(problem, lobe, energy, options.max_refinements, evaluations);

  // Optional extra starts (studies of the fit, not the bake): each refined, the best kept.
  uint64_t state = options.seed;
  for (int k = 0; k < options.random_starts; ++k) {
    Lobe trial = random_start(problem, state);
    double trial_energy = problem.energy(trial);  // also leaves the workspace holding `trial`
    ++evaluations;
    refine(problem, trial, trial_energy, options.max_refinements, evaluations);
    if (trial_energy < energy) {
      lobe = trial;
      energy = trial_energy;
    }
  }
  result.params = to_params(lobe);
  result.rms_error = std::sqrt(energy / double(k_count));
  result.evaluations = evaluations;
  return result;
}

}  // namespace clothbake::raycast

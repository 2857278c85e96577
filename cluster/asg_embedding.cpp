// ASG parameter embedding (asg_embedding.hpp).
#include "cluster/asg_embedding.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace clothbake::cluster {

void embed_asg(const model::AsgParams<double>& params, const AsgEmbeddingWeights& weights,
               float* out) {
  const model::Asg<double> g = model::asg_from_params(params);
  const double l1 = std::log1p(g.lambda), l2 = std::log1p(g.mu);
  const double s = 0.5 * (l1 + l2), a = 0.5 * (l1 - l2);
  const model::Vec3d& x = g.x;
  const model::Vec3d& y = g.y;
  const double r2 = std::sqrt(2.0);
  // U = (x x^T - y y^T) / sqrt(2); vec(U) with off-diagonals scaled by sqrt(2).
  const double uxx = (x.x * x.x - y.x * y.x) / r2;
  const double uyy = (x.y * x.y - y.y * y.y) / r2;
  const double uzz = (x.z * x.z - y.z * y.z) / r2;
  const double uxy = (x.x * x.y - y.x * y.y);  // sqrt2 * (...) / sqrt2
  const double uxz = (x.x * x.z - y.x * y.z);
  const double uyz = (x.y * x.z - y.y * y.z);
  const double wa = weights.axis, wb = weights.bandwidth * r2;
  out[0] = float(wa * g.z.x);
  out[1] = float(wa * g.z.y);
  out[2] = float(wa * g.z.z);
  out[3] = float(wb * s);
  out[4] = float(wb * a * uxx);
  out[5] = float(wb * a * uyy);
  out[6] = float(wb * a * uzz);
  out[7] = float(wb * a * uxy);
  out[8] = float(wb * a * uxz);
  out[9] = float(wb * a * uyz);
  out[10] = float(weights.amplitude * g.amplitude);
}

std::vector<float> embed_asgs(std::span<const model::AsgParams<float>> params,
                              const AsgEmbeddingWeights& weights) {
  std::vector<float> out(params.size() * kAsgEmbeddingDim);
  for (std::size_t i = 0; i < params.size(); ++i) {
    const auto& p = params[i];
    const float values[] = {p.axis.x, p.axis.y, p.axis.z, p.rotation, p.lambda, p.mu, p.amplitude};
    for (float v : values)
      if (!std::isfinite(v))
        throw_input_error("visibility ASG of texel " + std::to_string(i) +
                          " has a non-finite parameter");
    embed_asg(model::AsgParams<double>{model::Vec3d(p.axis), double(p.rotation), double(p.lambda),
                                       double(p.mu), double(p.amplitude)},
              weights, &out[i * kAsgEmbeddingDim]);
  }
  return out;
}

}  // namespace clothbake::cluster

// The parameter-space embedding of ASG visibility lobes used for the visibility clustering
// (paper Sec. 4.2: "the L2 difference between their set of parameters, namely orthogonal axis,
// rotation angle, and bandwidth").
//
// An ASG (model/asg.hpp) G(v) = c [v.z > 0] exp(-lambda (v.x)^2 - mu (v.y)^2) has symmetries that
// raw parameters do not respect: the rotation psi of the tangent axes is pi-periodic (x -> -x,
// y -> -y give the same lobe), swapping (lambda, x) with (mu, y) is the same lobe (psi + pi/2),
// and psi has no meaning for an isotropic lobe. The embedding maps every equivalent parameter set
// to the same point and is continuous, so that Euclidean distances are meaningful:
//
//   l1 = log(1 + lambda), l2 = log(1 + mu)              (bandwidths on a log scale; log1p keeps 0)
//   s  = (l1 + l2) / 2,   a = (l1 - l2) / 2              (mean and half-difference)
//   U  = (x x^T - y y^T) / sqrt(2)                        (unit Frobenius norm; symmetric,
//                                                          traceless, unchanged by x -> -x or
//                                                          y -> -y, negated by the x/y swap)
//   e  = [ w_axis z (3),  w_bw sqrt(2) s (1),  w_bw sqrt(2) a vec(U) (6),  w_amp c (1) ]
//
// vec(U) lists (Uxx, Uyy, Uzz, sqrt2 Uxy, sqrt2 Uxz, sqrt2 Uyz), so |vec(U)| = |U|_F = 1. The swap
// negates both a and U, so a U is invariant; for an isotropic lobe a = 0 and the orientation
// drops out. For two lobes with the same axis and orientation, the bandwidth part of the distance
// is w_bw |(l1, l2) - (l1', l2')|; a rotation by delta psi about a common axis adds
// 4 w_bw^2 a a' (1 - cos 2 delta psi) to the squared distance (pi-periodic in delta psi). U is
// built from the frame itself, not from psi, so it has no seam where the basis of the axis
// (orthonormal_basis) jumps. The lobe axis z is not sign-symmetric (the lobe covers the hemisphere
// around z) and enters as is.
//
// Header and source are C++20; safe on any finite parameters (non-finite ones are the caller's
// error, see embed_asgs).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "model/asg.hpp"

namespace clothbake::cluster {

inline constexpr std::size_t kAsgEmbeddingDim = 11;

// Relative weights of the three parameter groups (defaults in docs/tables.md, "ASG embedding").
struct AsgEmbeddingWeights {
  double axis = 1.0;       // chord distance between unit axes (0..2)
  double bandwidth = 0.5;  // per unit of log(1 + bandwidth)
  double amplitude = 1.0;  // per unit of amplitude
};

// The embedding of one lobe (kAsgEmbeddingDim floats written to out).
void embed_asg(const model::AsgParams<double>& params, const AsgEmbeddingWeights& weights,
               float* out);

// Embeddings of many lobes, row-major (count x kAsgEmbeddingDim). Throws clothbake::Error(Input)
// naming the texel if a parameter is not finite.
std::vector<float> embed_asgs(std::span<const model::AsgParams<float>> params,
                              const AsgEmbeddingWeights& weights);

}  // namespace clothbake::cluster

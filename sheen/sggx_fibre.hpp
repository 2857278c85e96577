// The fibre-like SGGX microflake distribution of the sheen layer (Heitz et al. 2015, "The SGGX
// Microflake Distribution"), for fibres standing along the macro normal z: S = diag(1, 1, sigma^2)
// with the SGGX fibre parameter sigma in [0, 1] (sigma = 1: spherical flakes, isotropic
// scattering; sigma -> 0: needle-thin vertical fibres whose flake normals are all horizontal).
// Zeltner et al. 2022 map the artist's sheen roughness r to sigma = r^2.
//
// Conventions follow Heitz et al.: directions point away from the scattering point; the projected
// area is sigma(w) = sqrt(w^T S w) (extinction = density * sigma(w)); D(m) is normalised so that
// integral <w, m>+ D(m) dm = sigma(w); the specular phase function is D(h) / (4 sigma(wi)).
//
// Visible normals are drawn geometrically: SGGX normals are the normals of the ellipsoid
// E = S^(-1/2) (unit sphere). Lines parallel to wi through E map to lines parallel to S^(1/2) wi
// through the unit sphere, with uniform cross-section measure kept uniform, so a point drawn
// uniformly on the projected disk of the sphere (a cosine-weighted point on the hemisphere facing
// w' = S^(1/2) wi) maps to a point uniform on the projected ellipse; its ellipsoid normal is
// S^(1/2) p. For diagonal S this needs no division by sigma and stays exact as sigma -> 0.
// Tests compare it with the closed-form D by chi-square.
//
// Inputs are unit vectors; safe for any sigma in [0, 1].
#pragma once

#include <algorithm>
#include <cmath>

#include "model/vec.hpp"

namespace clothbake::sheen {

using Vec3d = model::Vec3<double>;
inline constexpr double kPi = 3.14159265358979323846;

struct VerticalFibreSggx {
  double sigma = 1.0;  // SGGX fibre parameter: S = diag(1, 1, sigma^2)

  // Zeltner et al. 2022: sigma = roughness^2, roughness in [0, 1].
  static VerticalFibreSggx from_roughness(double roughness) {
    return VerticalFibreSggx{roughness * roughness};
  }

  // Projected area sigma(w) = sqrt(w^T S w) of the microflakes seen from w (unit vector).
  double projected_area(const Vec3d& w) const {
    return std::sqrt(w.x * w.x + w.y * w.y + sigma * sigma * w.z * w.z);
  }

  // Microflake normal distribution D(m) = 1 / (pi sqrt|S| (m^T S^-1 m)^2)
  //   = sigma^3 / (pi (sigma^2 (m.x^2 + m.y^2) + m.z^2)^2). Infinite (a delta) at sigma = 0.
  double ndf(const Vec3d& m) const {
    const double s2 = sigma * sigma;
    const double den = s2 * (m.x * m.x + m.y * m.y) + m.z * m.z;
    return sigma * s2 / (kPi * den * den);
  }

  // Density of visible normals seen from wi: <wi, m>+ D(m) / sigma(wi).
  double visible_ndf(const Vec3d& wi, const Vec3d& m) const {
    const double c = model::dot(wi, m);
    return c > 0.0 ? c * ndf(m) / projected_area(wi) : 0.0;
  }

  // Draws a visible normal for wi from two uniform numbers in [0, 1) (see the file comment).
  Vec3d sample_visible_normal(const Vec3d& wi, double u1, double u2) const {
    const Vec3d w = model::normalize(Vec3d{wi.x, wi.y, sigma * wi.z});
    Vec3d t1, t2;
    model::orthonormal_basis(w, t1, t2);
    const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
    const double px = r * std::cos(phi), py = r * std::sin(phi);
    const double pz = std::sqrt(std::max(0.0, 1.0 - px * px - py * py));
    const Vec3d p = t1 * px + t2 * py + w * pz;
    return model::normalize(Vec3d{p.x, p.y, sigma * p.z});
  }

  // Specular microflake phase function p(wi -> wo) = D(h) / (4 sigma(wi)), h = (wi + wo) / |.|.
  double phase(const Vec3d& wi, const Vec3d& wo) const {
    const Vec3d h = wi + wo;
    const double len = model::length(h);
    if (!(len > 0.0)) return 0.0;
    return ndf(h / len) / (4.0 * projected_area(wi));
  }

  // Draws wo from the phase function of wi: mirror wi about a visible normal.
  Vec3d sample_phase(const Vec3d& wi, double u1, double u2) const {
    const Vec3d m = sample_visible_normal(wi, u1, u2);
    return model::normalize(m * (2.0 * model::dot(m, wi)) - wi);
  }
};

}  // namespace clothbake::sheen

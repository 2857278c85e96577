// The model's parameters as text, for the command line and reports: parsing lobe and sheen
// convention names, and checking a texel's parameters with a message naming the field. Kept out of
// the shading headers (cloth_bsdf.hpp, sheen.hpp) so that a renderer's evaluator needs no
// std::string.
#pragma once

#include <string>

#include "model/cloth_bsdf.hpp"

namespace clothbake::model {

// Which parameter is wrong, and why; field is empty when the parameters are valid.
struct ParamsProblem {
  std::string field;    // "tangent", "roughness", "optical_thickness", "specular_albedo", ...
  std::string message;  // human-readable reason, without the field name
  bool ok() const { return field.empty(); }
};

// Checks the ranges documented on TexelParams (finite values; T may be +inf). Does not check the
// energy condition alpha + R_d + T_d <= 1 (see energy_excess).
template <class T>
inline ParamsProblem validate_texel_params(const TexelParams<T>& p) {
  auto unit_range = [](T v) { return v >= T(0) && v <= T(1); };
  auto rgb_unit = [&](const Rgb<T>& c) {
    return unit_range(c.r) && unit_range(c.g) && unit_range(c.b);
  };
  const T tl = length(p.tangent);
  if (!std::isfinite(tl) || !(tl > T(0))) return {"tangent", "must be a finite non-zero vector"};
  if (!roughness_in_range(double(p.roughness))) return {"roughness", "must be in [1e-4, 1]"};
  if (!(p.optical_thickness >= T(0))) return {"optical_thickness", "must be >= 0 (inf allowed)"};
  if (!rgb_unit(p.specular_albedo)) return {"specular_albedo", "components must be in [0, 1]"};
  if (!rgb_unit(p.diffuse_reflectance))
    return {"diffuse_reflectance", "components must be in [0, 1]"};
  if (!rgb_unit(p.diffuse_transmittance))
    return {"diffuse_transmittance", "components must be in [0, 1]"};
  if (!unit_range(p.gap)) return {"gap", "must be in [0, 1]"};
  if (!rgb_unit(p.sheen_color)) return {"sheen_color", "components must be in [0, 1]"};
  if (!roughness_in_range(double(p.sheen_roughness)))
    return {"sheen_roughness", "must be in [1e-4, 1]"};
  return {};
}

// Parses a lobe name as printed by lobe_name; returns false for anything else.
inline bool parse_lobe(const std::string& name, Lobe& lobe) {
  for (int k = 0; k < kLobeCount; ++k)
    if (name == lobe_name(Lobe(k))) {
      lobe = Lobe(k);
      return true;
    }
  return false;
}

// Parses "published" or "converged"; returns false (and leaves `convention` alone) otherwise.
inline bool parse_sheen_convention(const std::string& name, SheenConvention& convention) {
  if (name == "published") {
    convention = SheenConvention::Published;
    return true;
  }
  if (name == "converged") {
    convention = SheenConvention::Converged;
    return true;
  }
  return false;
}

}  // namespace clothbake::model

// The accepted ranges of the roughness parameters, stated once (docs/model.md, "Parameter
// ranges"): the fabric loader, the `clothbake bsdf` options, the model's parameter check and the
// asset validator all accept exactly [kMinRoughness, 1] for the SGGX fibre roughness and the sheen
// roughness, so that nothing bakes that validate then rejects and nothing is clamped silently.
// C++17, header only.
#pragma once

namespace clothbake::model {

// Smallest fibre and sheen roughness accepted (sigma^3 must stay a normal float: 1e-12 > 1.2e-38;
// the SGGX factory's clamp, kMinFibreRoughness, is the same value).
inline constexpr double kMinRoughness = 1e-4;
inline constexpr double kMaxRoughness = 1.0;

// True for roughness values in [kMinRoughness, kMaxRoughness] (false for NaN).
constexpr bool roughness_in_range(double roughness) {
  return roughness >= kMinRoughness && roughness <= kMaxRoughness;
}

}  // namespace clothbake::model

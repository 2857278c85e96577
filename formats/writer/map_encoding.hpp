// Encoders of the 16-bit codes of the feature maps (which compress/map_entropy.hpp then codes; the
// decoders and the exact definitions: formats/reader/map_encoding.hpp, docs/format.md, "Feature
// maps").
//
// Error bounds against the f32 value (tested in tests/formats/test_map_encoding.cpp):
//   height (f16)           |h' - h| <= 2^-11 |h| (<= 2^-25 where |h| < 2^-14)
//   tangent, normal (oct)  angle(v', v) <= 5.0e-5 rad (measured maximum 4.3e-5 rad)
//   gap, albedo (unorm16)  |x' - x| <= 1/131070 + 2^-24 (0 and 1 exact)
//
// C++20, pure functions, safe for any input: callers refuse NaN/Inf first (fabric_sections.cpp).
#pragma once

#include <cstdint>

namespace clothbake::formats {

// round(65535 x) of x clamped to [0, 1].
uint16_t float_to_unorm16(float x);

// The octahedral snorm16 codes of the direction of v (normalised here; a zero vector gives the
// codes of +z). Of the four codes around the exact point, the one whose decoded vector (as the
// reader decodes it) is nearest v in angle, so the bound above holds for the reader's result.
void unit_to_octahedral(const float v[3], int16_t out[2]);

}  // namespace clothbake::formats

// IEEE 754 binary16 encoding (reader::Half; the reader decodes with half_to_float): the compressed
// tables' basis (compress/) and the f16 codes of the height map (map_encoding.hpp). Round to
// nearest, ties to even; values beyond the largest half (65504) become +-Inf, which callers avoid
// by normalising to [-1, 1] first.
//
// C++20, header-only, pure functions; safe for any input (NaN stays NaN).
#pragma once

#include <bit>
#include <cstdint>

#include "formats/reader/asset.hpp"

namespace clothbake::formats {

inline reader::Half float_to_half(float value) {
  const uint32_t f = std::bit_cast<uint32_t>(value);
  const uint32_t sign = (f >> 16) & 0x8000u;
  const uint32_t abs = f & 0x7fffffffu;
  uint16_t bits;
  if (abs >= 0x7f800000u) {  // Inf or NaN
    bits = uint16_t(sign | 0x7c00u | (abs > 0x7f800000u ? 0x200u : 0u));
  } else if (abs >= 0x477ff000u) {  // rounds to >= 65520: overflow to Inf
    bits = uint16_t(sign | 0x7c00u);
  } else if (abs >= 0x38800000u) {  // normal half (>= 2^-14)
    const uint32_t mantissa = abs & 0x7fffffu;
    const uint32_t exponent = (abs >> 23) - 127 + 15;
    uint32_t h = (exponent << 10) | (mantissa >> 13);
    const uint32_t rest = mantissa & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // carries into the exponent
    bits = uint16_t(sign | h);
  } else if (abs >= 0x33000000u) {  // subnormal half (rounds to >= 2^-25)
    const uint32_t exponent = abs >> 23;
    const uint32_t mantissa = (abs & 0x7fffffu) | 0x800000u;
    const uint32_t shift = 126 - exponent;  // value = mantissa * 2^(exponent - 150) = h * 2^-24
    uint32_t h = mantissa >> shift;
    const uint32_t rest = mantissa & ((1u << shift) - 1u);
    const uint32_t half_way = 1u << (shift - 1);
    if (rest > half_way || (rest == half_way && (h & 1u))) ++h;
    bits = uint16_t(sign | h);
  } else {
    bits = uint16_t(sign);  // rounds to zero
  }
  return reader::Half{bits};
}

}  // namespace clothbake::formats

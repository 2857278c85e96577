// float -> IEEE binary16 encoding (compress/half_float.hpp) against the reader's decoder.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "compress/half_float.hpp"

namespace clothbake::compress {
namespace {

TEST(HalfFloat, EveryFiniteHalfRoundTrips) {
  for (uint32_t bits = 0; bits < 0x10000u; ++bits) {
    if ((bits & 0x7c00u) == 0x7c00u) continue;  // Inf / NaN
    const float f = reader::half_to_float(reader::Half{uint16_t(bits)});
    EXPECT_EQ(float_to_half(f).bits, bits) << "half bits " << bits;
  }
}

TEST(HalfFloat, RoundsToNearestTiesToEven) {
  // Midpoints between consecutive halves (normal and subnormal) go to the even neighbour, points
  // just above a midpoint go up.
  for (uint32_t bits : {0x0001u, 0x0002u, 0x03ffu, 0x0400u, 0x3c00u, 0x3c01u, 0x7bfeu}) {
    const double lo = reader::half_to_float(reader::Half{uint16_t(bits)});
    const double hi = reader::half_to_float(reader::Half{uint16_t(bits + 1)});
    const float mid = float((lo + hi) / 2);
    const uint16_t even = (bits & 1u) ? uint16_t(bits + 1) : uint16_t(bits);
    EXPECT_EQ(float_to_half(mid).bits, even) << bits;
    EXPECT_EQ(float_to_half(std::nextafter(mid, 1e9f)).bits, bits + 1) << bits;
    EXPECT_EQ(float_to_half(std::nextafter(mid, -1e9f)).bits, bits) << bits;
  }
}

TEST(HalfFloat, OverflowUnderflowAndSpecials) {
  EXPECT_EQ(float_to_half(65504.0f).bits, 0x7bffu);
  EXPECT_EQ(float_to_half(65519.0f).bits, 0x7bffu);
  EXPECT_EQ(float_to_half(65520.0f).bits, 0x7c00u);  // ties to even = Inf
  EXPECT_EQ(float_to_half(1e10f).bits, 0x7c00u);
  EXPECT_EQ(float_to_half(-1e10f).bits, 0xfc00u);
  EXPECT_EQ(float_to_half(std::ldexp(1.0f, -25)).bits, 0x0000u);  // half of the smallest: even
  EXPECT_EQ(float_to_half(std::ldexp(1.5f, -25)).bits, 0x0001u);
  EXPECT_EQ(float_to_half(1e-30f).bits, 0x0000u);
  EXPECT_EQ(float_to_half(-0.0f).bits, 0x8000u);
  EXPECT_EQ(float_to_half(std::numeric_limits<float>::infinity()).bits, 0x7c00u);
  EXPECT_TRUE(std::isnan(reader::half_to_float(float_to_half(std::nanf("")))));
}

}  // namespace
}  // namespace clothbake::compress

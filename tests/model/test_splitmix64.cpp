// The project's seeded RNG (model/splitmix64.hpp): the published SplitMix64 sequence, and the
// multiply-shift range reduction against an exact 128-bit product computed by hand, so that the
// portable fallback of mul_high_u64 and the __int128 path cannot disagree.
#include <gtest/gtest.h>

#include "model/splitmix64.hpp"

namespace {

using clothbake::model::mul_high_u64;
using clothbake::model::SplitMix64;

TEST(SplitMix64, MatchesTheReferenceSequenceForSeedZero) {
  SplitMix64 rng(0);
  EXPECT_EQ(rng.next(), 0xe220a8397b1dcdafull);
  EXPECT_EQ(rng.next(), 0x6e789e6aa1b965f4ull);
  EXPECT_EQ(rng.next(), 0x06c45d188009454full);
}

// Schoolbook 32-bit limbs: the exact high word of a * b.
uint64_t reference_mul_high(uint64_t a, uint64_t b) {
  const uint64_t a0 = a & 0xffffffffu, a1 = a >> 32, b0 = b & 0xffffffffu, b1 = b >> 32;
  const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const uint64_t middle = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
  return p11 + (p01 >> 32) + (p10 >> 32) + (middle >> 32);
}

TEST(SplitMix64, MulHighIsTheExactHighWord) {
  SplitMix64 rng(7);
  const uint64_t edges[] = {0, 1, 2, 0xffffffffull, 0x100000000ull, ~0ull, ~0ull - 1};
  for (uint64_t a : edges)
    for (uint64_t b : edges)
      EXPECT_EQ(mul_high_u64(a, b), reference_mul_high(a, b)) << a << " * " << b;
  for (int i = 0; i < 10000; ++i) {
    const uint64_t a = rng.next(), b = rng.next();
    ASSERT_EQ(mul_high_u64(a, b), reference_mul_high(a, b)) << a << " * " << b;
  }
}

TEST(SplitMix64, BelowStaysInRangeAndUniformInTheUnitInterval) {
  SplitMix64 rng(3);
  for (uint64_t n : {uint64_t(1), uint64_t(7), uint64_t(1) << 40, ~uint64_t(0)})
    for (int i = 0; i < 1000; ++i)
      ASSERT_LT(rng.below(n), n);
  for (int i = 0; i < 1000; ++i) {
    const double u = rng.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

}  // namespace

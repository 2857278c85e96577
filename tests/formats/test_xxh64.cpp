// The reader's own XXH64 against Debian's libxxhash: every length 0..1024 (all tail paths and
// stripe counts), several seeds, large random buffers, and streaming with every split point.
#include <gtest/gtest.h>
#include <xxhash.h>

#include <cstdint>
#include <random>
#include <vector>

#include "formats/validate/xxh64.hpp"

namespace {

std::vector<unsigned char> random_bytes(std::size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<unsigned char> v(n);
  for (auto& b : v)
    b = static_cast<unsigned char>(rng());
  return v;
}

TEST(Xxh64, KnownValuesOfTheSpecification) {
  // Reference values of XXH64 (seed 0) published with xxHash.
  EXPECT_EQ(clothbake::reader::xxh64("", 0, 0), 0xEF46DB3751D8E999ull);
  EXPECT_EQ(clothbake::reader::xxh64("a", 1, 0), 0xD24EC4F1A98C6E5Bull);
  EXPECT_EQ(clothbake::reader::xxh64("abc", 3, 0), 0x44BC2CF5AD770999ull);
}

TEST(Xxh64, MatchesLibxxhashForEveryShortLengthAndSeveralSeeds) {
  const auto data = random_bytes(1024 + 7, 1);
  for (uint64_t seed : {uint64_t(0), uint64_t(1), uint64_t(0x9E3779B97F4A7C15ull)})
    for (std::size_t n = 0; n <= 1024; ++n)
      // Offset 3: unaligned input too.
      ASSERT_EQ(clothbake::reader::xxh64(data.data() + 3, n, seed), XXH64(data.data() + 3, n, seed))
          << "length " << n << " seed " << seed;
}

TEST(Xxh64, MatchesLibxxhashOnLargeBuffers) {
  for (std::size_t n : {std::size_t(1) << 16, (std::size_t(1) << 20) + 13}) {
    const auto data = random_bytes(n, uint32_t(n));
    EXPECT_EQ(clothbake::reader::xxh64(data.data(), n, 0), XXH64(data.data(), n, 0));
  }
}

TEST(Xxh64, StreamingEqualsOneShotAtEverySplit) {
  const auto data = random_bytes(200, 7);
  const uint64_t expected = XXH64(data.data(), data.size(), 5);
  for (std::size_t a = 0; a <= data.size(); ++a)
    for (std::size_t b = a; b <= data.size(); b += 17) {
      clothbake::reader::Xxh64Stream s(5);
      s.update(data.data(), a);
      s.update(data.data() + a, b - a);
      s.update(data.data() + b, data.size() - b);
      ASSERT_EQ(s.digest(), expected) << "splits " << a << ", " << b;
    }
}

TEST(Xxh64, StreamingByteByByte) {
  const auto data = random_bytes(100, 9);
  clothbake::reader::Xxh64Stream s;
  for (unsigned char c : data)
    s.update(&c, 1);
  EXPECT_EQ(s.digest(), XXH64(data.data(), data.size(), 0));
}

}  // namespace

// A tiny deterministic random-number generator for the randomised steps of the bake (k-means++
// seeding, verify sampling): SplitMix64 (Steele, Lea and Flood 2014). Unlike the standard
// distributions (whose algorithms are implementation-defined), every value here is specified
// bit for bit, so seeds give the same results with every compiler and standard library.
#pragma once

#include <cstdint>

namespace clothbake::cluster {

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}

  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }
  // Uniform integer in [0, n) for n > 0 (multiply-shift; bias below 2^-64 * n).
  uint64_t below(uint64_t n) {
    return uint64_t((static_cast<unsigned __int128>(next()) * n) >> 64);
  }

 private:
  uint64_t state_;
};

}  // namespace clothbake::cluster

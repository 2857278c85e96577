// A small deterministic random number generator for the sheen layer simulation: xoshiro256++
// (Blackman and Vigna 2019) seeded through the project's SplitMix64 (model/splitmix64.hpp), so that
// a (seed, stream) pair gives the same sequence on every platform and thread count. The generator
// stays xoshiro256++ (not SplitMix64 itself) because the committed sheen table
// (model/sheen_table.hpp) was fitted from its streams. Not cryptographic.
#pragma once

#include <cstdint>

#include "model/splitmix64.hpp"

namespace clothbake::sheen {

class Rng {
 public:
  // One independent stream per (seed, stream): e.g. stream = table entry index.
  Rng(uint64_t seed, uint64_t stream) {
    uint64_t s = seed ^ (stream * 0xD1B54A32D192ED03ull + 0x8BB84B93962EACC9ull);
    for (uint64_t& word : state_)
      word = model::splitmix64_next(s);
  }

  uint64_t next_u64() {
    const uint64_t result = rotl(state_[0] + state_[3], 23) + state_[0];
    const uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  // Uniform double in [0, 1) with 53 random bits.
  double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t state_[4];
};

}  // namespace clothbake::sheen

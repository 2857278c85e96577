// The project's seeded random-number generator: SplitMix64 (Steele, Lea and Flood 2014), for every
// randomised step (k-means++ seeding, randomised SVD, verify's footprint sampling, the ASG fit's
// random restarts, the seeding of the sheen simulation's xoshiro streams). Unlike the standard
// distributions (whose algorithms are implementation-defined), every value here is specified bit
// for bit, so seeds give the same results with every compiler and standard library.
//
// Here in model/ (header-only, C++17, standard library only) rather than in common/ so that the
// reader library, the evaluator and a renderer can use the same generator without the baker's
// dependencies.
#pragma once

#include <cstdint>

namespace clothbake::model {

// One SplitMix64 step: advances `state` and returns the next 64-bit output. For generators that
// keep their own state word (the sheen simulation seeds xoshiro256++ with it).
inline uint64_t splitmix64_next(uint64_t& state) noexcept {
  uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// High 64 bits of the exact 128-bit product a * b (portable; exact either way, so the results
// do not depend on the compiler having a 128-bit integer).
inline uint64_t mul_high_u64(uint64_t a, uint64_t b) noexcept {
#if defined(__SIZEOF_INT128__)
  return uint64_t((static_cast<unsigned __int128>(a) * b) >> 64);
#else
  const uint64_t a_lo = a & 0xffffffffull, a_hi = a >> 32;
  const uint64_t b_lo = b & 0xffffffffull, b_hi = b >> 32;
  const uint64_t lo_lo = a_lo * b_lo, hi_lo = a_hi * b_lo, lo_hi = a_lo * b_hi;
  const uint64_t cross = (lo_lo >> 32) + (hi_lo & 0xffffffffull) + lo_hi;
  return a_hi * b_hi + (hi_lo >> 32) + (cross >> 32);
#endif
}

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  // The state: SplitMix64(g.state()) continues g's sequence (for callers that keep the state in a
  // plain integer, such as the C interface).
  uint64_t state() const { return state_; }

  // The next 64 random bits.
  uint64_t next() { return splitmix64_next(state_); }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }
  // Uniform integer in [0, n) for n > 0 (multiply-shift; bias below 2^-64 * n).
  uint64_t below(uint64_t n) { return mul_high_u64(next(), n); }

 private:
  uint64_t state_;
};

}  // namespace clothbake::model

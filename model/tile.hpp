// The tile wraps: texel indices on a periodic grid of n texels a side.
#pragma once

#include <cstdint>

namespace clothbake::model {

// i modulo n in [0, n), for any i (negative too) and n > 0. Pure, constexpr.
constexpr int64_t wrap_index(int64_t i, int64_t n) noexcept {
  const int64_t r = i % n;
  return r < 0 ? r + n : r;
}

}  // namespace clothbake::model

// XXH64 from the public specification (see xxh64.hpp). Reads are done with memcpy so that any
// alignment is fine; compilers turn them into plain loads.
#include "formats/validate/xxh64.hpp"

#include <cstring>

namespace clothbake::reader {
namespace {

constexpr uint64_t kPrime1 = 0x9E3779B185EBCA87ull;
constexpr uint64_t kPrime2 = 0xC2B2AE3D27D4EB4Full;
constexpr uint64_t kPrime3 = 0x165667B19E3779F9ull;
constexpr uint64_t kPrime4 = 0x85EBCA77C2B2AE63ull;
constexpr uint64_t kPrime5 = 0x27D4EB2F165667C5ull;

inline uint64_t rotl(uint64_t x, int r) {
  return (x << r) | (x >> (64 - r));
}

// The format is little-endian; the reader refuses big-endian hosts elsewhere, but keep the hash
// itself portable.
inline uint64_t load64_le(const unsigned char* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  v = __builtin_bswap64(v);
#endif
  return v;
}
inline uint32_t load32_le(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  v = __builtin_bswap32(v);
#endif
  return v;
}

inline uint64_t round(uint64_t acc, uint64_t input) {
  acc += input * kPrime2;
  acc = rotl(acc, 31);
  return acc * kPrime1;
}

inline uint64_t merge_round(uint64_t acc, uint64_t lane) {
  acc ^= round(0, lane);
  return acc * kPrime1 + kPrime4;
}

// Consumes whole 32-byte stripes; returns the number of bytes consumed.
inline std::size_t consume_stripes(uint64_t lanes[4], const unsigned char* p, std::size_t size) {
  uint64_t v1 = lanes[0], v2 = lanes[1], v3 = lanes[2], v4 = lanes[3];
  std::size_t done = 0;
  while (size - done >= 32) {
    const unsigned char* s = p + done;
    v1 = round(v1, load64_le(s));
    v2 = round(v2, load64_le(s + 8));
    v3 = round(v3, load64_le(s + 16));
    v4 = round(v4, load64_le(s + 24));
    done += 32;
  }
  lanes[0] = v1, lanes[1] = v2, lanes[2] = v3, lanes[3] = v4;
  return done;
}

inline void init_lanes(uint64_t lanes[4], uint64_t seed) {
  lanes[0] = seed + kPrime1 + kPrime2;
  lanes[1] = seed + kPrime2;
  lanes[2] = seed;
  lanes[3] = seed - kPrime1;
}

inline uint64_t converge(const uint64_t lanes[4]) {
  uint64_t acc = rotl(lanes[0], 1) + rotl(lanes[1], 7) + rotl(lanes[2], 12) + rotl(lanes[3], 18);
  for (int i = 0; i < 4; ++i)
    acc = merge_round(acc, lanes[i]);
  return acc;
}

// Remaining < 32 bytes, then the avalanche.
inline uint64_t finish(uint64_t acc, const unsigned char* p, std::size_t size) {
  while (size >= 8) {
    acc ^= round(0, load64_le(p));
    acc = rotl(acc, 27) * kPrime1 + kPrime4;
    p += 8, size -= 8;
  }
  if (size >= 4) {
    acc ^= uint64_t(load32_le(p)) * kPrime1;
    acc = rotl(acc, 23) * kPrime2 + kPrime3;
    p += 4, size -= 4;
  }
  while (size > 0) {
    acc ^= uint64_t(*p) * kPrime5;
    acc = rotl(acc, 11) * kPrime1;
    ++p, --size;
  }
  acc ^= acc >> 33;
  acc *= kPrime2;
  acc ^= acc >> 29;
  acc *= kPrime3;
  acc ^= acc >> 32;
  return acc;
}

}  // namespace

uint64_t xxh64(const void* data, std::size_t size, uint64_t seed) noexcept {
  const auto* p = static_cast<const unsigned char*>(data);
  uint64_t acc;
  std::size_t done = 0;
  if (size >= 32) {
    uint64_t lanes[4];
    init_lanes(lanes, seed);
    done = consume_stripes(lanes, p, size);
    acc = converge(lanes);
  } else {
    acc = seed + kPrime5;
  }
  acc += uint64_t(size);
  return finish(acc, p + done, size - done);
}

Xxh64Stream::Xxh64Stream(uint64_t seed) noexcept : seed_(seed) {
  init_lanes(lanes_, seed);
}

void Xxh64Stream::update(const void* data, std::size_t size) noexcept {
  if (size == 0) return;
  const auto* p = static_cast<const unsigned char*>(data);
  total_ += size;
  if (buffered_ > 0) {
    std::size_t take = 32 - buffered_ < size ? 32 - buffered_ : size;
    std::memcpy(buffer_ + buffered_, p, take);
    buffered_ += take, p += take, size -= take;
    if (buffered_ < 32) return;
    consume_stripes(lanes_, buffer_, 32);
    buffered_ = 0;
  }
  std::size_t done = consume_stripes(lanes_, p, size);
  std::memcpy(buffer_, p + done, size - done);
  buffered_ = size - done;
}

uint64_t Xxh64Stream::digest() const noexcept {
  uint64_t acc = total_ >= 32 ? converge(lanes_) : seed_ + kPrime5;
  acc += total_;
  return finish(acc, buffer_, buffered_);
}

}  // namespace clothbake::reader

// XXH64, the 64-bit xxHash of Yann Collet, implemented from the public specification
// (github.com/Cyan4973/xxHash, doc/xxhash_spec.md) so that the reader libraries need no third-party
// code. It is the checksum of the asset format (header, table and every section). The writer uses
// Debian's libxxhash; tests/formats/test_xxh64.cpp cross-checks both on many lengths and seeds.
//
// C++17, standard library only. Safe on any input: reads exactly `size` bytes from `data`.
#pragma once

#include <cstddef>
#include <cstdint>

namespace clothbake::reader {

// One-shot XXH64 of `size` bytes at `data` (data may be null when size is 0).
uint64_t xxh64(const void* data, std::size_t size, uint64_t seed = 0) noexcept;

// Streaming XXH64: update() any number of times, digest() gives the same value as the one-shot
// hash of the concatenated input. Copyable; no allocation.
class Xxh64Stream {
 public:
  explicit Xxh64Stream(uint64_t seed = 0) noexcept;
  void update(const void* data, std::size_t size) noexcept;
  uint64_t digest() const noexcept;

 private:
  uint64_t lanes_[4];
  uint64_t seed_;
  uint64_t total_ = 0;
  unsigned char buffer_[32];
  std::size_t buffered_ = 0;
};

}  // namespace clothbake::reader

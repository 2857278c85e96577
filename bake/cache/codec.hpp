// Serialisers of artifact values for the content-keyed cache (docs/batch.md, "Cache"), keyed by
// the value's C++ type, not by artifact name: a new stage whose outputs have types that already
// have a codec is cached with no edit here; an output type without one makes that stage run
// uncached (correct, only slower). A codec must encode every field that can differ between two
// values (the encoding is also what a content digest hashes).
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <typeindex>
#include <typeinfo>
#include <vector>

#include <xxhash.h>

#include "bake/pipeline/artifacts.hpp"
#include "common/error.hpp"

namespace clothbake::cache {

// Little-endian (host order on the supported x86-64/aarch64 Linux) byte buffer, or, when built
// with a hash state, a stream into XXH3-128 (content digests hash an encoding without holding it).
class ByteWriter {
 public:
  ByteWriter() = default;
  explicit ByteWriter(XXH3_state_t* hash) : hash_(hash) {}
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(&v, sizeof(T));
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    put(s.data(), s.size());
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    pod(uint64_t(v.size()));
    put(v.data(), v.size() * sizeof(T));
  }
  void span(std::span<const std::byte> b) {
    pod(uint64_t(b.size()));
    put(b.data(), b.size());
  }
  // Zero bytes up to the next multiple of `alignment` after `extra` more bytes (payloads that a
  // reader may map in place start aligned).
  void pad_before(uint64_t extra, uint64_t alignment) {
    static const std::byte zeros[64] = {};
    const uint64_t n = (alignment - (size_ + extra) % alignment) % alignment;
    pod(n);
    put(zeros, std::size_t(n));
  }
  std::vector<std::byte>& bytes() { return bytes_; }
  uint64_t size() const { return size_; }

 private:
  void put(const void* p, std::size_t n) {
    size_ += n;
    if (hash_) {
      XXH3_128bits_update(hash_, p, n);
      return;
    }
    const auto* b = static_cast<const std::byte*>(p);
    bytes_.insert(bytes_.end(), b, b + n);
  }
  std::vector<std::byte> bytes_;
  XXH3_state_t* hash_ = nullptr;
  uint64_t size_ = 0;
};

// Reads what ByteWriter wrote; every read is bounds-checked (Error(Input) "truncated").
// A reader over memory that stays mapped while `owner` lives may lend spans of it (borrow) to
// values that keep `owner` (large section payloads are then not copied).
class ByteReader {
 public:
  ByteReader(const std::byte* data, std::size_t size, std::shared_ptr<const void> owner = nullptr)
      : p_(data), end_(data + size), owner_(std::move(owner)) {}
  const std::shared_ptr<const void>& owner() const { return owner_; }
  // What pad_before wrote.
  void skip_pad() {
    const uint64_t n = pod<uint64_t>();
    if (n >= 64) throw_input_error("bad padding");
    need(n);
    p_ += n;
  }
  // The next u64-length-prefixed bytes (as written by span or vec<std::byte>), in place.
  std::span<const std::byte> borrow() {
    const uint64_t n = pod<uint64_t>();
    need(n);
    std::span<const std::byte> out(p_, std::size_t(n));
    p_ += n;
    return out;
  }
  template <class T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    return v;
  }
  std::string str() {
    const uint64_t n = pod<uint64_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(p_), std::size_t(n));
    p_ += n;
    return s;
  }
  template <class T>
  std::vector<T> vec() {
    const uint64_t n = pod<uint64_t>();
    if (n > uint64_t(end_ - p_) / sizeof(T)) throw_input_error("truncated value");
    std::vector<T> v;
    if constexpr (sizeof(T) == 1) {  // copy without zero-filling first (payloads are large)
      const auto* first = reinterpret_cast<const T*>(p_);
      v.assign(first, first + n);
    } else {
      v.resize(static_cast<std::size_t>(n));
      if (n) std::memcpy(v.data(), p_, std::size_t(n) * sizeof(T));
    }
    p_ += n * sizeof(T);
    return v;
  }
  // A u64 count of items that each take at least `min_bytes` of what is left: refused
  // (Error(Input) "truncated") when they cannot fit, so that a claimed count never allocates more
  // than the entry's own size.
  std::size_t count(std::size_t min_bytes) {
    const uint64_t n = pod<uint64_t>();
    if (min_bytes > 0 && n > uint64_t(end_ - p_) / min_bytes) throw_input_error("truncated value");
    return std::size_t(n);
  }
  bool done() const { return p_ == end_; }

 private:
  void need(uint64_t n) const {
    if (n > uint64_t(end_ - p_)) throw_input_error("truncated value");
  }
  const std::byte* p_;
  const std::byte* end_;
  std::shared_ptr<const void> owner_;
};

struct Codec {
  const std::type_info* type = nullptr;  // of the value
  std::string tag;  // stable name of the encoding, stored in cache entries ("json", "fabric/1")
  std::function<void(const pipeline::Artifacts&, const std::string& name, ByteWriter&)> encode;
  // Decodes a whole value and stores it in `out` under `name`; throws on malformed bytes.
  std::function<void(ByteReader&, pipeline::Artifacts& out, const std::string& name)> decode;
};

class Codecs {
 public:
  // Registers the codec of T (encode: value -> bytes; decode: bytes -> value).
  template <class T>
  void add(const std::string& tag, std::function<void(const T&, ByteWriter&)> encode,
           std::function<T(ByteReader&)> decode) {
    Codec c;
    c.type = &typeid(T);
    c.tag = tag;
    c.encode = [encode](const pipeline::Artifacts& a, const std::string& name, ByteWriter& w) {
      encode(a.get<T>(name), w);
    };
    c.decode = [decode](ByteReader& r, pipeline::Artifacts& out, const std::string& name) {
      out.put<T>(name, decode(r));
    };
    by_type_.insert_or_assign(std::type_index(typeid(T)), c);
    by_tag_.insert_or_assign(tag, std::type_index(typeid(T)));
  }
  // The codec for the value stored under `name`, or nullptr.
  const Codec* for_artifact(const pipeline::Artifacts& a, const std::string& name) const {
    auto it = by_type_.find(std::type_index(a.type_of(name)));
    return it == by_type_.end() ? nullptr : &it->second;
  }
  const Codec* for_tag(const std::string& tag) const {
    auto it = by_tag_.find(tag);
    return it == by_tag_.end() ? nullptr : &by_type_.at(it->second);
  }

 private:
  std::map<std::type_index, Codec> by_type_;
  std::map<std::string, std::type_index> by_tag_;
};

// Codecs of the types of the folders below bake/cache: std::string, std::vector<std::string>,
// nlohmann::json, std::vector<formats::Section>, Fabric. bake/stages adds the algorithm types.
void add_basic_codecs(Codecs& codecs);

}  // namespace clothbake::cache

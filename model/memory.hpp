// Where the reader and the evaluator get their memory: an allocator the caller may supply (the C
// interface's cb_allocator, docs/integration.md "Memory"), and an owning array that allocates
// through it without throwing. Nothing here throws: a failed allocation is a `false` the caller
// turns into its own error.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <utility>

namespace clothbake::model {

// A pair of functions that hand out and take back memory. `allocate` returns `size` bytes aligned
// to `alignment` (a power of two, at most 64) or null; `release` frees what it returned (never
// called with null). Both may be called from any thread that opens an asset, creates an
// evaluator, or estimates (the evaluator builds some of its sums on first use).
struct Allocator {
  void* (*allocate)(void* user, std::size_t size, std::size_t alignment) = nullptr;
  void (*release)(void* user, void* pointer) = nullptr;
  void* user = nullptr;
};

// The allocator used where the caller gives none: std::aligned_alloc and std::free. Thread-safe.
inline const Allocator& default_allocator() noexcept {
  struct Functions {
    static void* allocate(void*, std::size_t size, std::size_t alignment) noexcept {
      // aligned_alloc wants a size that is a multiple of the alignment.
      if (size > SIZE_MAX - (alignment - 1)) return nullptr;
      const std::size_t rounded = (size + alignment - 1) / alignment * alignment;
      return std::aligned_alloc(alignment, rounded == 0 ? alignment : rounded);
    }
    static void release(void*, void* pointer) noexcept { std::free(pointer); }
  };
  static constexpr Allocator kDefault{&Functions::allocate, &Functions::release, nullptr};
  return kDefault;
}

// An owning array of `size()` values of T in memory from an Allocator (the allocator must outlive
// the array). Move-only; never throws: allocate() answers false when the allocator returns null
// or the byte count overflows. The values are value-initialised (zero for arithmetic types; T's
// default constructor, which must not throw, otherwise) and destroyed with the array. Not
// thread-safe to allocate or reset while others read; reading from many threads is.
template <class T>
class Buffer {
 public:
  Buffer() noexcept = default;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& other) noexcept { swap(other); }
  Buffer& operator=(Buffer&& other) noexcept {
    Buffer(std::move(other)).swap(*this);
    return *this;
  }
  ~Buffer() { reset(); }

  // Replaces the contents with `count` value-initialised values from `allocator` (the default
  // allocator when null); false, and empty, when the memory cannot be had.
  bool allocate(std::size_t count, const Allocator* allocator = nullptr) noexcept {
    reset();
    allocator_ = allocator != nullptr ? allocator : &default_allocator();
    if (count == 0) return true;
    if (count > SIZE_MAX / sizeof(T)) return false;
    constexpr std::size_t alignment = alignof(T) < 8 ? 8 : alignof(T);
    void* memory = allocator_->allocate(allocator_->user, count * sizeof(T), alignment);
    if (memory == nullptr) return false;
    data_ = static_cast<T*>(memory);
    for (std::size_t i = 0; i < count; ++i)
      new (data_ + i) T();
    size_ = count;
    return true;
  }

  // The same, each value set to `value`.
  bool assign(std::size_t count, const T& value, const Allocator* allocator = nullptr) noexcept {
    if (!allocate(count, allocator)) return false;
    for (std::size_t i = 0; i < count; ++i)
      data_[i] = value;
    return true;
  }

  // Destroys the values and gives the memory back; the array is then empty.
  void reset() noexcept {
    if (data_ != nullptr) {
      for (std::size_t i = size_; i > 0; --i)
        data_[i - 1].~T();
      allocator_->release(allocator_->user, data_);
    }
    data_ = nullptr;
    size_ = 0;
  }

  void swap(Buffer& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
    std::swap(allocator_, other.allocator_);
  }

  T* data() noexcept { return data_; }
  const T* data() const noexcept { return data_; }
  T* get() noexcept { return data_; }
  const T* get() const noexcept { return data_; }
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  explicit operator bool() const noexcept { return data_ != nullptr; }
  T& operator[](std::size_t i) noexcept { return data_[i]; }
  const T& operator[](std::size_t i) const noexcept { return data_[i]; }
  T* begin() noexcept { return data_; }
  T* end() noexcept { return data_ + size_; }
  const T* begin() const noexcept { return data_; }
  const T* end() const noexcept { return data_ + size_; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
  const Allocator* allocator_ = nullptr;
};

// One object of T, constructed from `arguments` (by a constructor that does not throw), in
// memory from `allocator`; null when the memory cannot be had. Free it with destroy_object and
// the same allocator.
template <class T, class... Arguments>
T* create_object(const Allocator& allocator, Arguments&&... arguments) noexcept {
  void* memory = allocator.allocate(allocator.user, sizeof(T), alignof(T) < 8 ? 8 : alignof(T));
  return memory != nullptr ? new (memory) T(std::forward<Arguments>(arguments)...) : nullptr;
}

template <class T>
void destroy_object(const Allocator& allocator, T* object) noexcept {
  if (object == nullptr) return;
  object->~T();
  allocator.release(allocator.user, object);
}

}  // namespace clothbake::model

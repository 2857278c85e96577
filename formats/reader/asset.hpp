// The clothbake asset reader: opens a format-2 asset from a file (mmap on POSIX) or from a
// caller's buffer and gives zero-copy, typed access to its sections.
//
// Contract (the reader core, clothbake_reader, and its opt-in libraries clothbake_reader_raw and
// clothbake_reader_validate):
//  - C++17, standard library only; no exceptions leave the API (every entry point is noexcept and
//    returns a Status).
//  - Heap allocation only where a coded section is decoded, always from the asset's allocator
//    (set_allocator; model/memory.hpp, the default one aligned_alloc), sized from shapes already
//    checked, a failure returned as a Status (never a throw):
//    read_feature_maps (the decoded maps, CBK-E024), CompressedRadianceTables::open (SATs, basis,
//    cell map and coefficients; ErrorCode::Unsupported) and ParallaxView on the compressed table
//    (its block directory at open, each direction's decoded plane and SAT on first use).
//    Everything else (Asset, the other views, the raw tables' queries, the checksums, Status)
//    allocates nothing:
//    open_file maps the file (mmap) and views point into it, so a hostile file cannot cause a
//    huge allocation except as the decoded size of coded sections that passed every shape check
//    (each bounded: docs/format.md).
//  - Safe on untrusted bytes: open() checks the header, the table and every offset and size
//    (overflow-safe) before anything is dereferenced; a bad file yields a Status with a stable
//    check ID, never a crash or an out-of-bounds read. open() reads no payload byte and verifies
//    no checksum: that is opt-in (formats/validate/checksums.hpp, clothbake_reader_validate).
//  - Views point into the mapped file or the caller's buffer: they are valid while the Asset (and,
//    for open_memory, the buffer) lives. A mapped file must not be truncated by another process
//    while open (POSIX delivers SIGBUS); clothbake's writer never modifies an asset in place.
//  - Little-endian hosts only (open() refuses big-endian hosts with ErrorCode::Unsupported).
//  - An Asset is immutable after open(): concurrent reads from several threads are safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "formats/reader/layout.hpp"
#include "formats/reader/status.hpp"
#include "model/memory.hpp"

namespace clothbake::reader {

// IEEE binary16 element (ElementType::F16); convert with half_to_float().
struct Half {
  uint16_t bits;
};
float half_to_float(Half h) noexcept;

// ElementTypeOf<T>::value: the ElementType a view of T reads.
template <class T>
struct ElementTypeOf;
template <>
struct ElementTypeOf<uint8_t> {
  static constexpr ElementType value = ElementType::U8;
};
template <>
struct ElementTypeOf<int8_t> {
  static constexpr ElementType value = ElementType::I8;
};
template <>
struct ElementTypeOf<uint16_t> {
  static constexpr ElementType value = ElementType::U16;
};
template <>
struct ElementTypeOf<int16_t> {
  static constexpr ElementType value = ElementType::I16;
};
template <>
struct ElementTypeOf<uint32_t> {
  static constexpr ElementType value = ElementType::U32;
};
template <>
struct ElementTypeOf<int32_t> {
  static constexpr ElementType value = ElementType::I32;
};
template <>
struct ElementTypeOf<uint64_t> {
  static constexpr ElementType value = ElementType::U64;
};
template <>
struct ElementTypeOf<int64_t> {
  static constexpr ElementType value = ElementType::I64;
};
template <>
struct ElementTypeOf<Half> {
  static constexpr ElementType value = ElementType::F16;
};
template <>
struct ElementTypeOf<float> {
  static constexpr ElementType value = ElementType::F32;
};
template <>
struct ElementTypeOf<double> {
  static constexpr ElementType value = ElementType::F64;
};

// One decoded table entry plus a pointer to its stored bytes (inside the asset).
struct SectionInfo {
  uint32_t index = 0;  // position in the table
  SectionType type{};
  uint32_t instance = 0;
  uint16_t version = 0;
  Codec codec{};
  ElementType element_type{};
  uint16_t rank = 0;
  uint32_t dims[kMaxRank] = {};
  uint64_t offset = 0;
  uint64_t stored_size = 0;
  uint64_t raw_size = 0;
  uint64_t checksum = 0;
  const unsigned char* data = nullptr;  // stored bytes, stored_size long

  // Product of the dims (1 for rank 0). open() has checked it does not overflow.
  uint64_t element_count() const noexcept;
};

// A typed, zero-copy view of a Raw section: size elements of T, shape dims[0..rank).
template <class T>
struct ArrayView {
  const T* data = nullptr;
  uint64_t size = 0;
  uint16_t rank = 0;
  uint32_t dims[kMaxRank] = {};

  const T& operator[](uint64_t i) const noexcept { return data[i]; }
  const T* begin() const noexcept { return data; }
  const T* end() const noexcept { return data + size; }
  bool empty() const noexcept { return size == 0; }
};

class Asset {
 public:
  Asset() noexcept = default;
  ~Asset();
  Asset(Asset&& other) noexcept;
  Asset& operator=(Asset&& other) noexcept;
  Asset(const Asset&) = delete;
  Asset& operator=(const Asset&) = delete;

  // Maps the file read-only and checks its structure (header, version, table, every offset, size
  // and shape: O(section count)). Messages start with the path. On error the Asset stays closed.
  // Errors: Io (missing, not a regular file, cannot map) and every open_memory error.
  Status open_file(const char* path) noexcept;

  // Uses `size` bytes at `data` (not copied; must outlive the Asset and stay unchanged). `data`
  // must be 8-byte aligned (InvalidArgument otherwise) so that typed views are aligned.
  // Errors: NotAnAsset, Truncated, UnsupportedVersion, Malformed, Unsupported.
  Status open_memory(const void* data, std::size_t size) noexcept;

  void close() noexcept;
  bool is_open() const noexcept { return bytes_ != nullptr; }

  uint16_t version_major() const noexcept { return header_.version_major; }
  uint16_t version_minor() const noexcept { return header_.version_minor; }
  uint64_t file_size() const noexcept { return size_; }
  // The stored header checksum: a hash of the table, hence of every section's content (not
  // verified by open(); checksums.hpp verifies it).
  uint64_t content_hash() const noexcept { return header_.header_checksum; }
  const FileHeader& header() const noexcept { return header_; }
  // The whole file (file_size() bytes).
  const unsigned char* bytes() const noexcept { return bytes_; }

  uint32_t section_count() const noexcept { return header_.section_count; }
  // Table entry `index` (< section_count()); InvalidArgument otherwise.
  Status section(uint32_t index, SectionInfo* out) const noexcept;
  // The section of this type and instance (binary search); NotFound if absent.
  Status find(SectionType type, uint32_t instance, SectionInfo* out) const noexcept;

  // Typed view of a Raw section. Errors: NotFound, Unsupported (codec), WrongType (element type).
  template <class T>
  Status array(SectionType type, uint32_t instance, ArrayView<T>* out) const noexcept {
    SectionInfo info;
    Status status = typed_section(type, instance, ElementTypeOf<T>::value, &info);
    if (!status.ok()) return status;
    return view_of(info, out);
  }

  // Typed view of an already found section (same checks as array()).
  // Only info.index is used: the rest is re-read from the table.
  template <class T>
  Status view_of(const SectionInfo& info, ArrayView<T>* out) const noexcept {
    SectionInfo fresh;
    Status status = section(info.index, &fresh);
    if (status.ok()) status = check_view(fresh, ElementTypeOf<T>::value);
    if (!status.ok()) return status;
    out->data = reinterpret_cast<const T*>(fresh.data);
    out->size = fresh.element_count();
    out->rank = fresh.rank;
    for (uint32_t i = 0; i < kMaxRank; ++i)
      out->dims[i] = fresh.dims[i];
    return {};
  }

  // The Metadata section as text (UTF-8 JSON; not parsed here). NotFound if absent.
  Status metadata_json(std::string_view* out) const noexcept;

  // Where the views opened over this asset (decoded maps, tables, parallax) get their memory:
  // `allocator` (which must outlive the asset and every view over it), or the default allocator
  // when null (the initial state). Kept by close() and moves; set it before opening views.
  void set_allocator(const model::Allocator* allocator) noexcept { allocator_ = allocator; }
  const model::Allocator* allocator() const noexcept {
    return allocator_ != nullptr ? allocator_ : &model::default_allocator();
  }

 private:
  Status typed_section(SectionType type, uint32_t instance, ElementType element,
                       SectionInfo* out) const noexcept;
  Status check_view(const SectionInfo& info, ElementType element) const noexcept;
  SectionEntry entry(uint32_t index) const noexcept;

  const unsigned char* bytes_ = nullptr;
  std::size_t size_ = 0;
  FileHeader header_{};
  void* mapping_ = nullptr;  // owned mapping (open_file), else null
  std::size_t mapping_size_ = 0;
  const model::Allocator* allocator_ = nullptr;
};

}  // namespace clothbake::reader

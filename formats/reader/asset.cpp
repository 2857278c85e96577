// Asset: opening, structural checks and section lookup (asset.hpp states the contract).
//
// Every size computation below is done in uint64_t with explicit overflow checks before any
// pointer is formed from it: the bytes come from an untrusted file.
#include "formats/reader/asset.hpp"

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>

#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#define CLOTHBAKE_READER_POSIX 1
#endif

namespace clothbake::reader {
namespace {

bool host_is_little_endian() noexcept {
  const uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// a * b into *out; false on overflow.
bool mul_overflows(uint64_t a, uint64_t b, uint64_t* out) noexcept {
  if (a != 0 && b > UINT64_MAX / a) return true;
  *out = a * b;
  return false;
}

bool known_element_type(uint16_t type) noexcept {
  return type <= uint16_t(ElementType::F64);
}

}  // namespace

float half_to_float(Half h) noexcept {
  const uint32_t sign = uint32_t(h.bits & 0x8000u) << 16;
  const uint32_t exponent = (h.bits >> 10) & 0x1fu;
  uint32_t mantissa = h.bits & 0x3ffu;
  uint32_t bits;
  if (exponent == 0x1f) {
    bits = sign | 0x7f800000u | (mantissa << 13);  // Inf or NaN
  } else if (exponent != 0) {
    bits = sign | ((exponent + 112) << 23) | (mantissa << 13);
  } else if (mantissa == 0) {
    bits = sign;  // +-0
  } else {
    // Subnormal: normalise.
    int shift = 0;
    while ((mantissa & 0x400u) == 0)
      mantissa <<= 1, ++shift;
    mantissa &= 0x3ffu;
    bits = sign | (uint32_t(113 - shift) << 23) | (mantissa << 13);
  }
  float value;
  std::memcpy(&value, &bits, 4);
  return value;
}

uint64_t SectionInfo::element_count() const noexcept {
  uint64_t count = 1;
  for (uint32_t i = 0; i < rank && i < kMaxRank; ++i)
    count *= dims[i];
  return count;
}

Asset::~Asset() {
  close();
}

Asset::Asset(Asset&& other) noexcept {
  *this = static_cast<Asset&&>(other);
}

Asset& Asset::operator=(Asset&& other) noexcept {
  if (this != &other) {
    close();
    bytes_ = other.bytes_;
    size_ = other.size_;
    header_ = other.header_;
    mapping_ = other.mapping_;
    mapping_size_ = other.mapping_size_;
    allocator_ = other.allocator_;
    other.bytes_ = nullptr;
    other.size_ = 0;
    other.mapping_ = nullptr;
    other.mapping_size_ = 0;
  }
  return *this;
}

void Asset::close() noexcept {
#ifdef CLOTHBAKE_READER_POSIX
  if (mapping_) munmap(mapping_, mapping_size_);
#endif
  mapping_ = nullptr;
  mapping_size_ = 0;
  bytes_ = nullptr;
  size_ = 0;
  header_ = FileHeader{};
}

Status Asset::open_file(const char* path) noexcept {
  close();
  if (path == nullptr) return Status::error(ErrorCode::InvalidArgument, Check::None, "null path");
#ifdef CLOTHBAKE_READER_POSIX
  // O_NONBLOCK: opening a FIFO must not wait for a writer (it is then refused as not regular).
  int fd = ::open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    Status s = Status::error(ErrorCode::Io, Check::None, "cannot open: %s", std::strerror(errno));
    s.prefix(path);
    return s;
  }
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    Status s = Status::error(ErrorCode::Io, Check::None, "not a regular file");
    s.prefix(path);
    return s;
  }
  const std::size_t size = std::size_t(st.st_size);
  Status status;
  if (size == 0) {
    ::close(fd);
    static const uint64_t empty = 0;
    status = open_memory(&empty, 0);
  } else {
    void* map = mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    ::close(fd);
    if (map == MAP_FAILED) {
      Status s = Status::error(ErrorCode::Io, Check::None, "cannot map %zu bytes: %s", size,
                               std::strerror(errno));
      s.prefix(path);
      return s;
    }
    status = open_memory(map, size);
    if (status.ok()) {
      mapping_ = map;
      mapping_size_ = size;
    } else {
      munmap(map, size);
    }
  }
  if (!status.ok()) status.prefix(path);
  return status;
#else
  Status s = Status::error(ErrorCode::Unsupported, Check::None,
                           "open_file needs POSIX mmap on this platform; use open_memory");
  s.prefix(path);
  return s;
#endif
}

Status Asset::open_memory(const void* data, std::size_t size) noexcept {
  close();
  if (data == nullptr) return Status::error(ErrorCode::InvalidArgument, Check::None, "null buffer");
  if (reinterpret_cast<uintptr_t>(data) % 8 != 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "buffer is not 8-byte aligned (typed views would be misaligned)");
  if (!host_is_little_endian())
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "this reader supports little-endian hosts only");
  const auto* bytes = static_cast<const unsigned char*>(data);

  // Magic first (on whatever bytes exist), so that a short non-asset is "not an asset".
  const std::size_t magic_bytes = size < sizeof kMagic ? size : sizeof kMagic;
  if (std::memcmp(bytes, kMagic, magic_bytes) != 0)
    return Status::error(ErrorCode::NotAnAsset, Check::NotAnAsset,
                         "not a clothbake asset (wrong magic bytes)");
  if (size < sizeof(FileHeader))
    return Status::error(ErrorCode::Truncated, Check::Truncated,
                         "truncated: %zu bytes, the header alone is %zu", size, sizeof(FileHeader));

  FileHeader header;
  std::memcpy(&header, bytes, sizeof header);
  if (header.version_major != kFormatMajor) {
    const bool newer = header.version_major > kFormatMajor;
    return Status::error(
        ErrorCode::UnsupportedVersion, Check::UnsupportedMajor,
        "asset format %u.%u, this reader reads format %u.x: %s", unsigned(header.version_major),
        unsigned(header.version_minor), unsigned(kFormatMajor),
        newer ? "the asset is newer than this reader; rebuild the reader (update clothbake)"
              : "the asset is older than this reader; re-bake it from its fabric with this "
                "clothbake (clothbake bake FABRIC.toml -o ASSET.cbk)");
  }
  if (header.section_entry_size < kMinSectionEntrySize || header.section_entry_size % 8 != 0)
    return Status::error(ErrorCode::Malformed, Check::HeaderField,
                         "header: section_entry_size %u is not a multiple of 8 that is >= %u",
                         unsigned(header.section_entry_size), unsigned(kMinSectionEntrySize));
  if (header.section_count > kMaxSectionCount)
    return Status::error(ErrorCode::Malformed, Check::HeaderField,
                         "header: section_count %u exceeds the limit %u",
                         unsigned(header.section_count), unsigned(kMaxSectionCount));
  // Both factors are bounded (2^20 * 2^32), so this cannot overflow 64 bits.
  const uint64_t table_bytes = uint64_t(header.section_count) * header.section_entry_size;
  const uint64_t table_end = sizeof(FileHeader) + table_bytes;
  if (table_end > size)
    return Status::error(ErrorCode::Truncated, Check::Truncated,
                         "truncated: %zu bytes, the section table ends at byte %" PRIu64, size,
                         table_end);

  if (header.file_size % kSectionAlignment != 0 || header.file_size < table_end)
    return Status::error(ErrorCode::Malformed, Check::HeaderField,
                         "header: file_size %" PRIu64
                         " is not a multiple of 64 at or after the table end %" PRIu64,
                         header.file_size, table_end);
  if (size < header.file_size)
    return Status::error(ErrorCode::Truncated, Check::Truncated,
                         "truncated: %zu bytes, the header says %" PRIu64, size, header.file_size);
  if (size > header.file_size)
    return Status::error(ErrorCode::Malformed, Check::TrailingBytes,
                         "%" PRIu64
                         " unexpected bytes after the end of the asset (file_size %" PRIu64 ")",
                         uint64_t(size) - header.file_size, header.file_size);

  // Table entries: bounds, alignment, order, shape. Payloads start after the table, 64-aligned.
  const uint64_t data_start =
      (table_end + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment;
  const bool newer_minor = header.version_minor > kFormatMinor;
  uint64_t previous_end = data_start;
  uint64_t previous_key = 0;
  char what_buffer[96];
  for (uint32_t i = 0; i < header.section_count; ++i) {
    SectionEntry e;
    std::memcpy(&e, bytes + sizeof(FileHeader) + uint64_t(i) * header.section_entry_size, sizeof e);
    // Formatted only on the error paths: open() must stay O(1) per entry and cheap.
    auto what = [&] {
      return describe_section(what_buffer, sizeof what_buffer, i, e.type, e.instance);
    };
    if (e.offset % kSectionAlignment != 0)
      return Status::error(ErrorCode::Malformed, Check::SectionAlignment,
                           "%s: offset %" PRIu64 " is not a multiple of 64", what(), e.offset);
    if (e.offset < data_start || e.stored_size > header.file_size ||
        e.offset > header.file_size - e.stored_size)
      return Status::error(ErrorCode::Malformed, Check::SectionBounds,
                           "%s: bytes [%" PRIu64 ", +%" PRIu64
                           ") are outside the payload area [%" PRIu64 ", %" PRIu64 ")",
                           what(), e.offset, e.stored_size, data_start, header.file_size);
    if (e.offset < previous_end)
      return Status::error(ErrorCode::Malformed, Check::SectionOverlap,
                           "%s: starts at %" PRIu64 ", before the previous section ends (%" PRIu64
                           ")",
                           what(), e.offset, previous_end);
    previous_end = e.offset + e.stored_size;
    const uint64_t key = (uint64_t(e.type) << 32) | e.instance;
    if (i > 0 && key <= previous_key)
      return Status::error(ErrorCode::Malformed, Check::SectionOrder,
                           "%s: (type, instance) is not strictly after the previous entry's",
                           what());
    previous_key = key;

    // Shape.
    if (e.rank > kMaxRank)
      return Status::error(ErrorCode::Malformed, Check::SectionShape, "%s: rank %u exceeds %u",
                           what(), unsigned(e.rank), unsigned(kMaxRank));
    for (uint32_t d = e.rank; d < kMaxRank; ++d)
      if (e.dims[d] != 0)
        return Status::error(ErrorCode::Malformed, Check::SectionShape,
                             "%s: dims[%u] = %u is beyond rank %u (must be 0)", what(), unsigned(d),
                             unsigned(e.dims[d]), unsigned(e.rank));
    if (known_element_type(e.element_type)) {
      const auto element = ElementType(e.element_type);
      if (element == ElementType::Opaque) {
        if (e.rank != 0)
          return Status::error(ErrorCode::Malformed, Check::SectionShape,
                               "%s: an opaque payload must have rank 0, not %u", what(),
                               unsigned(e.rank));
      } else {
        if (e.rank == 0)
          return Status::error(ErrorCode::Malformed, Check::SectionShape,
                               "%s: a %s array needs rank >= 1", what(),
                               element_type_name(element));
        uint64_t expected = element_size(element);
        bool overflow = false;
        for (uint32_t d = 0; d < e.rank && !overflow; ++d)
          overflow = mul_overflows(expected, e.dims[d], &expected);
        if (overflow || expected != e.raw_size)
          return Status::error(ErrorCode::Malformed, Check::SectionShape,
                               "%s: raw_size %" PRIu64 " does not match its shape and %s elements",
                               what(), e.raw_size, element_type_name(element));
      }
    } else if (!newer_minor) {
      return Status::error(ErrorCode::Malformed, Check::SectionShape, "%s: unknown element type %u",
                           what(), unsigned(e.element_type));
    }
    if (e.codec == uint16_t(Codec::Raw)) {
      if (e.raw_size != e.stored_size)
        return Status::error(ErrorCode::Malformed, Check::SectionShape,
                             "%s: raw codec but raw_size %" PRIu64 " != stored_size %" PRIu64,
                             what(), e.raw_size, e.stored_size);
    } else if (!newer_minor) {
      return Status::error(ErrorCode::Malformed, Check::UnsupportedCodec,
                           "%s: codec %u is not defined in format %u.%u", what(), unsigned(e.codec),
                           unsigned(header.version_major), unsigned(header.version_minor));
    }
  }

  bytes_ = bytes;
  size_ = size;
  header_ = header;
  return {};
}

SectionEntry Asset::entry(uint32_t index) const noexcept {
  SectionEntry e;
  std::memcpy(&e, bytes_ + sizeof(FileHeader) + uint64_t(index) * header_.section_entry_size,
              sizeof e);
  return e;
}

Status Asset::section(uint32_t index, SectionInfo* out) const noexcept {
  if (!is_open() || out == nullptr || index >= header_.section_count)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "section index %u out of range (%u sections)", unsigned(index),
                         unsigned(header_.section_count));
  const SectionEntry e = entry(index);
  SectionInfo info;
  info.index = index;
  info.type = SectionType(e.type);
  info.instance = e.instance;
  info.version = e.version;
  info.codec = Codec(e.codec);
  info.element_type = ElementType(e.element_type);
  info.rank = e.rank;
  for (uint32_t d = 0; d < kMaxRank; ++d)
    info.dims[d] = e.dims[d];
  info.offset = e.offset;
  info.stored_size = e.stored_size;
  info.raw_size = e.raw_size;
  info.checksum = e.checksum;
  info.data = bytes_ + e.offset;
  *out = info;
  return {};
}

Status Asset::find(SectionType type, uint32_t instance, SectionInfo* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "asset not open");
  const uint64_t key = (uint64_t(type) << 32) | instance;
  uint32_t lo = 0, hi = header_.section_count;  // open() checked the keys are ascending
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    const SectionEntry e = entry(mid);
    const uint64_t k = (uint64_t(e.type) << 32) | e.instance;
    if (k == key) return section(mid, out);
    if (k < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  const char* name = section_type_name(type);
  if (name)
    return Status::error(ErrorCode::NotFound, Check::MissingSection, "no %s section (instance %u)",
                         name, unsigned(instance));
  return Status::error(ErrorCode::NotFound, Check::MissingSection,
                       "no section of type 0x%04x (instance %u)", unsigned(type),
                       unsigned(instance));
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
Status Asset::typed_section(SectionType type, uint32_t instance, ElementType element,
                            SectionInfo* out) const noexcept {
  Status status = find(type, instance, out);
  if (!status.ok()) return status;
  return check_view(*out, element);
}
#endif

Status Asset::check_view(const SectionInfo& info, ElementType element) const noexcept {
  char what[96];
  if (info.codec != Codec::Raw) {
    describe_section(what, sizeof what, info.index, uint32_t(info.type), info.instance);
    const char* codec = codec_name(info.codec);
    return Status::error(ErrorCode::Unsupported, Check::UnsupportedCodec,
                         "%s: codec %s (%u) is not supported by this reader", what,
                         codec ? codec : "unknown", unsigned(info.codec));
  }
  if (info.element_type != element) {
    describe_section(what, sizeof what, info.index, uint32_t(info.type), info.instance);
    const char* have = element_type_name(info.element_type);
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "%s: holds %s elements, %s were requested", what, have ? have : "unknown",
                         element_type_name(element));
  }
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
Status Asset::metadata_json(std::string_view* out) const noexcept {
  SectionInfo info;
  Status status = typed_section(SectionType::Metadata, 0, ElementType::U8, &info);
  if (!status.ok()) return status;
  *out = std::string_view(reinterpret_cast<const char*>(info.data), std::size_t(info.raw_size));
  return {};
}
#endif

}  // namespace clothbake::reader

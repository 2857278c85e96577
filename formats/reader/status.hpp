// Error reporting of the reader library: no exceptions and no allocation. Every failing call
// returns a Status with an error class, a stable check ID (docs/format.md, "Validation checks")
// and a human-readable message in a fixed buffer.
//
// C++17, standard library only.
#pragma once

#include <cstdint>

namespace clothbake::reader {

// Broad class of a failure (what a caller branches on).
enum class ErrorCode : uint8_t {
  Ok = 0,
  Io,                  // the file could not be opened, sized or mapped
  NotAnAsset,          // wrong magic: not a clothbake asset at all
  UnsupportedVersion,  // another major version of the format
  Truncated,           // the file is shorter than its structure says
  Corrupt,             // a checksum does not match
  Malformed,           // a structural rule of the format is broken (offsets, sizes, order, shape)
  Unsupported,         // valid, but this reader cannot decode it (codec, section version)
  NotFound,            // a requested section is absent
  WrongType,           // a section's element type or shape does not match the request
  InvalidArgument,     // a caller's argument is unusable (null pointer, misaligned buffer)
  OutOfPlan,           // a scene-planned asset left out what the query needs: a
                       // half-vector or view bin outside its bin map, or transmission
};

// Stable check IDs. The number is the ID ("CBK-E012" is Check::SectionChecksum); never renumber.
enum class Check : uint16_t {
  None = 0,
  // Errors.
  NotAnAsset = 1,         // CBK-E001 magic bytes do not match
  Truncated = 2,          // CBK-E002 file shorter than header, table or file_size
  UnsupportedMajor = 3,   // CBK-E003 format major version differs from the reader's
  HeaderChecksum = 4,     // CBK-E004 header/table checksum mismatch
  HeaderField = 5,        // CBK-E005 invalid header field (entry size, count, file_size)
  TrailingBytes = 6,      // CBK-E006 bytes after file_size
  SectionBounds = 7,      // CBK-E007 section outside the file or overlapping the table
  SectionAlignment = 8,   // CBK-E008 section offset not a multiple of 64
  SectionOverlap = 9,     // CBK-E009 sections overlap or are not in offset order
  SectionOrder = 10,      // CBK-E010 (type, instance) duplicated or not ascending
  SectionShape = 11,      // CBK-E011 rank/dims/element type/sizes inconsistent
  SectionChecksum = 12,   // CBK-E012 section payload checksum mismatch
  Padding = 13,           // CBK-E013 non-zero padding or reserved bytes
  UnsupportedCodec = 14,  // CBK-E014 codec unknown to this reader (asset not newer)
  SectionLayout = 15,     // CBK-E015 known section with wrong element type, shape or version
  MapResolution = 16,     // CBK-E016 feature maps disagree on the resolution
  NonFinite = 17,         // CBK-E017 NaN or Inf in a floating-point section
  YarnIdRange = 18,       // CBK-E018 yarn id without a material record
  MissingSection = 19,    // CBK-E019 a required section is absent
  Metadata = 20,          // CBK-E020 metadata is not a UTF-8 JSON object
  ValueRange = 21,        // CBK-E021 a parameter outside its documented range
  CrossSection = 22,      // CBK-E022 well-formed sections that disagree with each other
  MetadataSchema = 23,    // CBK-E023 a known metadata key of the wrong type; text not UTF-8
  ResourceLimit = 24,     // CBK-E024 a section that would decode to more than the reader's cap
  // Warnings (numbered from 1001; printed as CBK-W001...).
  UnknownSection = 1001,       // CBK-W001 section type unknown to this reader (skipped)
  NewerMinor = 1002,           // CBK-W002 asset written by a newer minor version
  UnknownCodecNewer = 1003,    // CBK-W003 unknown codec in a newer-minor asset (section skipped)
  NotUnitVector = 1004,        // CBK-W004 normal or tangent not of unit length
  NewerSectionVersion = 1005,  // CBK-W005 known section type with a newer version (skipped)
};

// "CBK-E012", "CBK-W001", or "" for Check::None. Static storage.
const char* check_id(Check check) noexcept;
// True for warnings (CBK-W...).
constexpr bool is_warning(Check check) {
  return uint16_t(check) > 1000;
}

class Status {
 public:
  static constexpr unsigned kMessageCapacity = 320;

  Status() noexcept { message_[0] = '\0'; }
  // printf-style message; truncated to the buffer if longer.
  static Status error(ErrorCode code, Check check, const char* format, ...) noexcept
#if defined(__GNUC__)
      __attribute__((format(printf, 3, 4)))
#endif
      ;

  bool ok() const noexcept {
    return code_ == ErrorCode::Ok;
  }
  ErrorCode code() const noexcept {
    return code_;
  }
  Check check() const noexcept {
    return check_;
  }
  const char* check_id() const noexcept {
    return reader::check_id(check_);
  }
  const char* message() const noexcept {
    return message_;
  }

  // Prefixes the message with "PREFIX: " (e.g. the file path).
  void prefix(const char* text) noexcept;

 private:
  ErrorCode code_ = ErrorCode::Ok;
  Check check_ = Check::None;
  char message_[kMessageCapacity];  // NUL-terminated; the rest is not initialised (cheap Ok)
};

}  // namespace clothbake::reader

// Writer of the clothbake asset container (format 2; docs/format.md). C++20.
//
// Sections are built in memory (make_*_section), then laid out deterministically: sorted by
// (type, instance), each at the next multiple of 64, zero padding, no timestamps or host names,
// XXH64 checksums from libxxhash. The same sections always give the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "formats/reader/asset.hpp"  // reader::Half, ElementTypeOf
#include "formats/reader/layout.hpp"
#include "formats/writer/sink.hpp"

namespace clothbake::formats {

using reader::ElementType;
using reader::SectionType;

// One section, ready to be written. Build it with the make_*_section functions, which enforce
// the invariants (shape matches payload, no NaN/Inf).
struct Section {
  SectionType type{};
  uint32_t instance = 0;
  uint16_t version = 1;
  ElementType element = ElementType::U8;
  std::vector<uint32_t> dims;  // rank = dims.size() <= 4; empty only for Opaque
  std::vector<std::byte> payload;
  // Instead of `payload` (which is then empty): bytes held elsewhere, valid while `mapped_owner`
  // lives (the stage cache hands out payloads of mapped entries this way, so that a large section
  // is written without a copy). Read a section's bytes through bytes(), which sees either form.
  std::span<const std::byte> mapped;
  std::shared_ptr<const void> mapped_owner;
  std::span<const std::byte> bytes() const {
    return mapped_owner ? mapped : std::span<const std::byte>(payload);
  }
};

// "height" or "type 0x0777", plus " instance I" when instance != 0: for messages.
std::string section_label(SectionType type, uint32_t instance);

// Why `s` cannot be written (rank above 4, version 0, an opaque payload with dims, a typed array
// without dims or of an unknown element type, both payload forms, a shape that overflows 64 bits
// or that does not match the payload's size), or "" when it can. Safe on any values (the stage
// cache checks decoded sections with it).
std::string section_problem(const Section& s);

// A typed-array section holding a copy of `values` with shape `dims` (slowest first). Elements are
// float, double, reader::Half or an integer type. Throws clothbake::Error:
//  - ExitCode::Input if a floating-point value is NaN or Inf, naming the section, the element
//    index and its multi-index ("height: element 17 [0, 17] is NaN");
//  - ExitCode::Internal if the dims do not match values.size() or the rank exceeds 4.
template <class T>
Section make_array_section(SectionType type, uint32_t instance, std::span<const T> values,
                           std::vector<uint32_t> dims, uint16_t version = 1);

// Records of a fixed-size struct (FabricInfoRecord, YarnMaterialRecord...) as a u8 array of shape
// {count, sizeof(Record)}. The caller zero-initialises records (padding must be zero).
template <class Record>
Section make_record_section(SectionType type, uint32_t instance, std::span<const Record> records,
                            uint16_t version = 1) {
  static_assert(std::is_trivially_copyable_v<Record>);
  std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(records.data()),
                                 records.size_bytes());
  return make_array_section<uint8_t>(type, instance, bytes,
                                     {uint32_t(records.size()), uint32_t(sizeof(Record))}, version);
}

// The Metadata section: `metadata` as UTF-8 JSON, keys sorted, 2-space indent (invalid UTF-8 in
// strings is replaced by U+FFFD rather than failing).
Section make_metadata_section(const nlohmann::json& metadata);

// The functions below come in two forms: over a contiguous array of sections, and over pointers
// to sections (`SectionRefs`), so that a caller holding sections in several containers (the bake's
// write stage) writes them without copying the payloads. Both forms give the same bytes for the
// same sections, in whatever order they are passed.
using SectionRefs = std::span<const Section* const>;

// Checks a set of sections for writing: rank <= 4, payload size = shape x element size, unique
// (type, instance). Throws Error(Internal) naming the section on failure (also for a null pointer).
void check_sections(std::span<const Section> sections);
void check_sections(SectionRefs sections);

// The table order: sections sorted by (type, instance). Pointers into `sections`.
std::vector<const Section*> table_order(std::span<const Section> sections);
std::vector<const Section*> table_order(SectionRefs sections);

// Bytes of a complete asset written through `sink` (header, table, payloads, padding). Returns
// the file size. Throws what the sink throws, and Error(Internal) for invalid sections.
uint64_t write_asset(std::span<const Section> sections, Sink& sink);
uint64_t write_asset(SectionRefs sections, Sink& sink);

// The asset in memory (for tests and the golden file).
std::vector<std::byte> serialize_asset(std::span<const Section> sections);

// Size the asset will have, without writing it.
uint64_t asset_size(std::span<const Section> sections);
uint64_t asset_size(SectionRefs sections);

// Writes the asset atomically to `path` (see atomic_file.hpp for the guarantees and errors).
struct OutputOptions;
void write_asset_file(const std::filesystem::path& path, std::span<const Section> sections,
                      const OutputOptions& options);
void write_asset_file(const std::filesystem::path& path, SectionRefs sections,
                      const OutputOptions& options);

}  // namespace clothbake::formats

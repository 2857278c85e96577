#include "formats/writer/asset_writer.hpp"

#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "common/error.hpp"
#include "formats/reader/asset.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::formats {
namespace {

using reader::kSectionAlignment;

uint64_t align_up(uint64_t value) {
  return (value + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment;
}

// "[3, 17]" for a flat index in a C-order shape.
std::string multi_index(uint64_t flat, const std::vector<uint32_t>& dims) {
  std::vector<uint64_t> idx(dims.size());
  for (std::size_t d = dims.size(); d-- > 0;) {
    const uint64_t extent = dims[d] ? dims[d] : 1;
    idx[d] = flat % extent;
    flat /= extent;
  }
  std::ostringstream out;
  out << '[';
  for (std::size_t d = 0; d < idx.size(); ++d)
    out << (d ? ", " : "") << idx[d];
  out << ']';
  return out.str();
}

template <class T>
bool is_finite_element(const T& value) {
  if constexpr (std::is_same_v<T, float> || std::is_same_v<T, double>)
    return std::isfinite(value);
  else if constexpr (std::is_same_v<T, reader::Half>)
    return ((value.bits >> 10) & 0x1f) != 0x1f;
  else
    return true;
}

template <class T>
const char* non_finite_kind(const T& value) {
  if constexpr (std::is_same_v<T, float> || std::is_same_v<T, double>)
    return std::isnan(value) ? "NaN" : "Inf";
  else if constexpr (std::is_same_v<T, reader::Half>)
    return (value.bits & 0x3ff) ? "NaN" : "Inf";
  else
    return "";
}

void check_section(const Section& s) {
  if (const std::string problem = section_problem(s); !problem.empty())
    throw_internal_error("section " + section_label(s.type, s.instance) + ": " + problem);
}

reader::SectionEntry entry_of(const Section& s, uint64_t offset) {
  reader::SectionEntry e;
  std::memset(&e, 0, sizeof e);
  e.type = uint32_t(s.type);
  e.version = s.version;
  e.codec = uint16_t(reader::Codec::Raw);
  e.offset = offset;
  const std::span<const std::byte> bytes = s.bytes();
  e.stored_size = bytes.size();
  e.checksum = XXH64(bytes.data(), bytes.size(), 0);
  e.raw_size = bytes.size();
  e.element_type = uint16_t(s.element);
  e.rank = uint16_t(s.dims.size());
  for (std::size_t d = 0; d < s.dims.size(); ++d)
    e.dims[d] = s.dims[d];
  e.instance = s.instance;
  return e;
}

}  // namespace

std::string section_label(SectionType type, uint32_t instance) {
  std::string label;
  if (const char* name = reader::section_type_name(type)) {
    label = name;
  } else {
    char buf[32];
    std::snprintf(buf, sizeof buf, "type 0x%04x", unsigned(type));
    label = buf;
  }
  if (instance != 0) label += " instance " + std::to_string(instance);
  return label;
}

std::string section_problem(const Section& s) {
  if (s.dims.size() > reader::kMaxRank)
    return "rank " + std::to_string(s.dims.size()) + " exceeds 4";
  if (s.version == 0) return "payload version 0";
  if (s.mapped_owner && !s.payload.empty()) return "both an owned and a mapped payload";
  if (s.element == ElementType::Opaque)
    return s.dims.empty() ? "" : "an opaque payload has no dims";
  if (s.dims.empty()) return "a typed array needs dims";
  uint64_t expected = reader::element_size(s.element);
  if (expected == 0) return "unknown element type";
  for (uint32_t d : s.dims) {
    if (d != 0 && expected > UINT64_MAX / d) return "shape overflows 64 bits";
    expected *= d;
  }
  if (expected != s.bytes().size())
    return "payload has " + std::to_string(s.bytes().size()) + " bytes, its shape needs " +
           std::to_string(expected);
  return "";
}

template <class T>
Section make_array_section(SectionType type, uint32_t instance, std::span<const T> values,
                           std::vector<uint32_t> dims, uint16_t version) {
  static_assert(std::is_trivially_copyable_v<T>);
  Section s;
  s.type = type;
  s.instance = instance;
  s.version = version;
  s.element = reader::ElementTypeOf<T>::value;
  s.dims = std::move(dims);
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!is_finite_element(values[i]))
      throw_input_error("refusing to write a non-finite value: section " +
                        section_label(type, instance) + " element " + std::to_string(i) + " " +
                        multi_index(i, s.dims) + " is " + non_finite_kind(values[i]));
  s.payload.resize(values.size_bytes());
  if (!values.empty()) std::memcpy(s.payload.data(), values.data(), values.size_bytes());
  check_section(s);
  return s;
}

#define CLOTHBAKE_INSTANTIATE(T)                                                    \
  template Section make_array_section<T>(SectionType, uint32_t, std::span<const T>, \
                                         std::vector<uint32_t>, uint16_t);
CLOTHBAKE_INSTANTIATE(uint8_t)
CLOTHBAKE_INSTANTIATE(int8_t)
CLOTHBAKE_INSTANTIATE(uint16_t)
CLOTHBAKE_INSTANTIATE(int16_t)
CLOTHBAKE_INSTANTIATE(uint32_t)
CLOTHBAKE_INSTANTIATE(int32_t)
CLOTHBAKE_INSTANTIATE(uint64_t)
CLOTHBAKE_INSTANTIATE(int64_t)
CLOTHBAKE_INSTANTIATE(reader::Half)
CLOTHBAKE_INSTANTIATE(float)
CLOTHBAKE_INSTANTIATE(double)
#undef CLOTHBAKE_INSTANTIATE

Section make_metadata_section(const nlohmann::json& metadata) {
  if (!metadata.is_object()) throw_internal_error("metadata must be a JSON object");
  const std::string text =
      metadata.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(text.data()), text.size());
  return make_array_section<uint8_t>(SectionType::Metadata, 0, bytes, {uint32_t(text.size())});
}

namespace {

std::vector<const Section*> pointers_to(std::span<const Section> sections) {
  std::vector<const Section*> refs;
  refs.reserve(sections.size());
  for (const Section& s : sections)
    refs.push_back(&s);
  return refs;
}

}  // namespace

void check_sections(SectionRefs sections) {
  for (const Section* s : sections) {
    if (s == nullptr) throw_internal_error("a null section was passed to the asset writer");
    check_section(*s);
  }
  const auto order = table_order(sections);
  for (std::size_t i = 1; i < order.size(); ++i)
    if (order[i]->type == order[i - 1]->type && order[i]->instance == order[i - 1]->instance)
      throw_internal_error("two sections " + section_label(order[i]->type, order[i]->instance));
  if (sections.size() > reader::kMaxSectionCount)
    throw_internal_error("too many sections: " + std::to_string(sections.size()));
}

void check_sections(std::span<const Section> sections) {
  check_sections(SectionRefs(pointers_to(sections)));
}

std::vector<const Section*> table_order(SectionRefs sections) {
  std::vector<const Section*> order(sections.begin(), sections.end());
  // Stable, so that the order (and the duplicate message) does not depend on the sort's whims.
  std::stable_sort(order.begin(), order.end(), [](const Section* a, const Section* b) {
    return std::pair(uint32_t(a->type), a->instance) < std::pair(uint32_t(b->type), b->instance);
  });
  return order;
}

std::vector<const Section*> table_order(std::span<const Section> sections) {
  return table_order(SectionRefs(pointers_to(sections)));
}

uint64_t asset_size(SectionRefs sections) {
  uint64_t offset =
      align_up(sizeof(reader::FileHeader) + sections.size() * sizeof(reader::SectionEntry));
  for (const Section* s : table_order(sections))
    offset = align_up(offset + s->bytes().size());
  return offset;
}

uint64_t asset_size(std::span<const Section> sections) {
  return asset_size(SectionRefs(pointers_to(sections)));
}

uint64_t write_asset(SectionRefs sections, Sink& sink) {
  check_sections(sections);
  const auto order = table_order(sections);
  const uint64_t table_end =
      sizeof(reader::FileHeader) + order.size() * sizeof(reader::SectionEntry);

  // Lay out and checksum everything first: the table (and the header checksum) precede payloads.
  std::vector<reader::SectionEntry> table;
  table.reserve(order.size());
  uint64_t offset = align_up(table_end);
  for (const Section* s : order) {
    table.push_back(entry_of(*s, offset));
    offset = align_up(offset + s->bytes().size());
  }
  const uint64_t file_size = offset;

  reader::FileHeader header;
  std::memset(&header, 0, sizeof header);
  std::memcpy(header.magic, reader::kMagic, sizeof header.magic);
  header.version_major = reader::kFormatMajor;
  header.version_minor = reader::kFormatMinor;
  header.section_count = uint32_t(order.size());
  header.section_entry_size = sizeof(reader::SectionEntry);
  header.flags = 0;
  header.file_size = file_size;
  XXH64_state_t* state = XXH64_createState();
  if (!state) throw std::bad_alloc();
  XXH64_reset(state, 0);
  XXH64_update(state, &header, reader::kHeaderChecksumOffset);
  XXH64_update(state, table.data(), table.size() * sizeof(reader::SectionEntry));
  header.header_checksum = XXH64_digest(state);
  XXH64_freeState(state);

  static const std::byte zeros[reader::kSectionAlignment] = {};
  uint64_t written = 0;
  auto put = [&](const void* data, uint64_t size) {
    if (size) sink.write(data, std::size_t(size));
    written += size;
  };
  put(&header, sizeof header);
  put(table.data(), table.size() * sizeof(reader::SectionEntry));
  for (std::size_t i = 0; i < order.size(); ++i) {
    put(zeros, table[i].offset - written);
    put(order[i]->bytes().data(), order[i]->bytes().size());
  }
  put(zeros, file_size - written);
  return file_size;
}

uint64_t write_asset(std::span<const Section> sections, Sink& sink) {
  return write_asset(SectionRefs(pointers_to(sections)), sink);
}

std::vector<std::byte> serialize_asset(std::span<const Section> sections) {
  MemorySink sink;
  write_asset(sections, sink);
  return std::move(sink.bytes());
}

void write_asset_file(const std::filesystem::path& path, SectionRefs sections,
                      const OutputOptions& options) {
  check_sections(sections);  // before creating anything
  write_file_atomically(
      path, [&](Sink& sink) { write_asset(sections, sink); }, options);
}

void write_asset_file(const std::filesystem::path& path, std::span<const Section> sections,
                      const OutputOptions& options) {
  const std::vector<const Section*> refs = pointers_to(sections);
  write_asset_file(path, SectionRefs(refs), options);
}

}  // namespace clothbake::formats

// Crafting hostile assets for tests, as an attacker would: read every section of a good asset,
// edit the payload or shape of some, and write them back with the writer, which recomputes every
// checksum (so the result passes the integrity checks and only the deeper rules can catch it).
#pragma once

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "formats/reader/asset.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::test_support {

// Every section of the asset at `path`, payloads copied (Raw codec only, as clothbake writes).
inline std::vector<formats::Section> sections_of(const std::filesystem::path& path) {
  reader::Asset asset;
  if (!asset.open_file(path.c_str()).ok()) throw std::runtime_error("cannot open " + path.string());
  std::vector<formats::Section> sections;
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    reader::SectionInfo s;
    if (!asset.section(i, &s).ok()) throw std::runtime_error("bad section");
    formats::Section out;
    out.type = s.type;
    out.instance = s.instance;
    out.version = s.version;
    out.element = s.element_type;
    out.dims.assign(s.dims, s.dims + s.rank);
    const auto* bytes = reinterpret_cast<const std::byte*>(s.data);
    out.payload.assign(bytes, bytes + s.stored_size);
    sections.push_back(std::move(out));
  }
  return sections;
}

// The section of `type` (instance 0) in `sections`; throws when absent.
inline formats::Section& section_of(std::vector<formats::Section>& sections,
                                    reader::SectionType type, uint32_t instance = 0) {
  for (auto& s : sections)
    if (s.type == type && s.instance == instance) return s;
  throw std::runtime_error("no such section");
}

// Writes `sections` as an asset at `path` (fresh checksums; no validation of the content).
inline void write_sections(const std::filesystem::path& path,
                           const std::vector<formats::Section>& sections) {
  const std::vector<std::byte> bytes = formats::serialize_asset(sections);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// A metadata section holding exactly `text` (not re-serialised: any bytes, any nesting).
inline formats::Section raw_metadata_section(const std::string& text) {
  formats::Section s;
  s.type = reader::SectionType::Metadata;
  s.element = reader::ElementType::U8;
  s.dims = {uint32_t(text.size())};
  const auto* bytes = reinterpret_cast<const std::byte*>(text.data());
  s.payload.assign(bytes, bytes + text.size());
  return s;
}

// Reads / writes a trivially copyable value at `offset` of a section's payload.
template <class T>
T get_at(const formats::Section& s, std::size_t offset) {
  T value;
  std::memcpy(&value, s.payload.data() + offset, sizeof value);
  return value;
}
template <class T>
void put_at(formats::Section& s, std::size_t offset, T value) {
  std::memcpy(s.payload.data() + offset, &value, sizeof value);
}

}  // namespace clothbake::test_support

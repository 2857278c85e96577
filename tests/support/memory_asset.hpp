// An asset serialised by the writer into 8-byte-aligned memory with the reader opened on it, for
// tests that build sections in memory (and edit them as an attacker would) without files.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "formats/reader/asset.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::test_support {

// The reader's view of `sections` written as one asset; `status` is what open_memory said.
struct MemoryAsset {
  std::vector<uint64_t> storage;  // 8-byte aligned, as the reader requires
  reader::Asset asset;
  reader::Status status;
  explicit MemoryAsset(const std::vector<formats::Section>& sections) {
    const std::vector<std::byte> bytes = formats::serialize_asset(sections);
    storage.resize((bytes.size() + 7) / 8);
    std::memcpy(storage.data(), bytes.data(), bytes.size());
    status = asset.open_memory(storage.data(), bytes.size());
  }
};

// `sections` with the metadata section every asset carries.
inline std::vector<formats::Section> with_metadata(std::vector<formats::Section> sections) {
  sections.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  return sections;
}

// The IDs (CBK-Ennn) of every finding of reader::validate_asset, each followed by a space.
inline std::string validate_ids(const reader::Asset& asset) {
  std::string ids;
  reader::validate_asset(
      asset,
      [](void* user, reader::Check check, uint32_t, const char*) {
        *static_cast<std::string*>(user) += std::string(reader::check_id(check)) + " ";
      },
      &ids);
  return ids;
}

}  // namespace clothbake::test_support

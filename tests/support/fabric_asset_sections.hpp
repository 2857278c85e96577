// The sections a bake writes for a fabric before any computed table: its records (fabric_info,
// yarn_materials) and its feature maps as format 2.0 stores them (entropy-coded 16-bit codes), for
// tests that build assets in memory. The caller adds the metadata section it wants.
#pragma once

#include <utility>
#include <vector>

#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::test_support {

inline std::vector<formats::Section> fabric_asset_sections(const Fabric& fabric) {
  std::vector<formats::Section> sections = fabric_record_sections(fabric);
  for (auto& s : compress::feature_map_sections(fabric.maps))
    sections.push_back(std::move(s));
  return sections;
}

}  // namespace clothbake::test_support

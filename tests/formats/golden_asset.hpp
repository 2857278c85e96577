// The small asset checked in as tests/formats/data/golden_v2.cbk (format 2.0): the 4 x 4 test
// fabric's records and coded feature maps plus a fixed metadata object (no tool version, so that a
// version bump does not change the bytes). Regenerate deliberately (docs/format.md, "Golden
// file"):
//   CLOTHBAKE_REGENERATE_GOLDEN=1 build-*/bin/formats_golden_test
// tests/formats/data/golden_v1.cbk is the format-1.0 file the same fabric gave before 2.0, kept
// to check that a 1.x asset is refused with a message that says to re-bake it.
#pragma once

#include <vector>

#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"
#include "tests/support/fabric_asset_sections.hpp"

namespace clothbake::test_support {

inline std::vector<formats::Section> golden_sections() {
  Fabric fabric = make_test_fabric(4, "golden");
  // The settings the checked-in file was written with (the metadata records them), whatever
  // today's defaults: the golden bytes test the writer, not the defaults.
  fabric.bake.visibility_dirs = 32;
  std::vector<formats::Section> sections = test_support::fabric_asset_sections(fabric);
  nlohmann::json metadata;
  metadata["format"] = "clothbake-asset";
  metadata["tool"] = {{"name", "clothbake"}, {"version", "golden"}};
  metadata["fabric"] = fabric_metadata(fabric);
  metadata["stages"] = {"load_fabric", "feature_maps", "write"};
  sections.push_back(formats::make_metadata_section(metadata));
  return sections;
}

inline std::string golden_path() {
  return CLOTHBAKE_SOURCE_DIR "/tests/formats/data/golden_v2.cbk";
}

// The format-1.0 file of the same fabric (read-only: no writer makes it any more).
inline std::string golden_v1_path() {
  return CLOTHBAKE_SOURCE_DIR "/tests/formats/data/golden_v1.cbk";
}

}  // namespace clothbake::test_support

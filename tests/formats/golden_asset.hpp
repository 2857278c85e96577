// The small assets checked in as tests/formats/data/golden_v1.cbk (format 1.0: f32 feature maps)
// and golden_v1_4.cbk (format 1.4: the same maps at reduced precision, payload version 2): the
// 4 x 4 test fabric's records and feature maps plus a fixed metadata object (no tool version, so
// that a version bump does not change the bytes). Regenerate deliberately (docs/format.md,
// "Golden file"):
//   CLOTHBAKE_REGENERATE_GOLDEN=1 build-*/bin/formats_golden_test
#pragma once

#include <vector>

#include "fabric/fabric_sections.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"

namespace clothbake::test_support {

inline std::vector<formats::Section> golden_sections(MapEncoding encoding = MapEncoding::Float32) {
  Fabric fabric = make_test_fabric(4, "golden");
  // The settings the checked-in files were written with (the metadata records them), whatever
  // today's defaults: the golden bytes test the writer, not the defaults.
  fabric.bake.visibility_dirs = 32;
  std::vector<formats::Section> sections = fabric_record_sections(fabric);
  for (auto& s : feature_map_sections(fabric.maps, encoding))
    sections.push_back(std::move(s));
  nlohmann::json metadata;
  metadata["format"] = "clothbake-asset";
  metadata["tool"] = {{"name", "clothbake"}, {"version", "golden"}};
  metadata["fabric"] = fabric_metadata(fabric);
  metadata["stages"] = {"load_fabric", "feature_maps", "write"};
  sections.push_back(formats::make_metadata_section(metadata));
  return sections;
}

inline std::string golden_path(MapEncoding encoding = MapEncoding::Float32) {
  return encoding == MapEncoding::Float32 ? CLOTHBAKE_SOURCE_DIR "/tests/formats/data/golden_v1.cbk"
                                          : CLOTHBAKE_SOURCE_DIR
             "/tests/formats/data/golden_v1_4.cbk";
}

}  // namespace clothbake::test_support

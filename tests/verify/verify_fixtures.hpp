// Test assets for verify: a procedural weave fabric, a synthetic label map and the tables baked
// from them with the library (no pipeline needed), as sections or bytes.
#pragma once

#include <functional>
#include <vector>

#include "bake/inputs/fabric_load.hpp"
#include "cluster/cluster_sections.hpp"
#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"
#include "tests/support/fabric_asset_sections.hpp"

namespace clothbake::verify_testing {

// Labels by 4 x 4 texel blocks, `clusters` of them.
inline std::vector<uint8_t> block_labels(int n, int clusters) {
  std::vector<uint8_t> labels;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      labels.push_back(uint8_t(((x / 4) + 2 * (y / 4)) % clusters));
  return labels;
}

// Every section of an asset for `fabric`: fabric records and maps, clusters (mean visibility 1)
// and the raw tables. `tamper` may edit the sections before they are returned.
inline std::vector<formats::Section> asset_sections(
    const Fabric& fabric, int clusters, const tables::RadianceOptions& options,
    const std::function<void(std::vector<formats::Section>&)>& tamper = {}) {
  const int n = fabric.maps.resolution;
  cluster::VisibilityClusters vc;
  vc.resolution = n;
  vc.clusters = clusters;
  vc.visibility_dirs = 4;
  vc.labels = block_labels(n, clusters);
  vc.mean_visibility.assign(std::size_t(clusters) * 16, 1.0f);
  std::vector<formats::Section> sections = test_support::fabric_asset_sections(fabric);
  for (auto& s : cluster::cluster_sections(vc))
    sections.push_back(std::move(s));
  auto inputs = tables::radiance_inputs(fabric, vc.labels, clusters);
  for (auto& set : tables::build_radiance_tables(inputs.view, options))
    for (auto& s : tables::radiance_sections(std::move(set)))
      sections.push_back(std::move(s));
  if (tamper) tamper(sections);
  return sections;
}

// The SAT section of a kind (instance kind * 16 + 3).
inline formats::Section* sat_section(std::vector<formats::Section>& sections, int kind) {
  for (auto& s : sections)
    if (s.type == reader::SectionType::RadianceRawTables && s.instance == uint32_t(kind * 16 + 3))
      return &s;
  return nullptr;
}

}  // namespace clothbake::verify_testing

// Asset sections of the raw Integral-Radiance tables (layout: formats/reader/radiance_layout.hpp)
// and the way back, for stages that read the tables from the pipeline (compress/).
#pragma once

#include <span>
#include <vector>

#include "formats/writer/asset_writer.hpp"
#include "tables/radiance_fill.hpp"

namespace clothbake::tables {

// The four sections of `set` (Info, Clusters, Units, Sat). The SAT payload is moved, not copied
// (it is the bulk of the asset); `set` is left without SAT data. An empty set (no stored
// clusters) gives no sections. Throws Error(Internal) if the set is inconsistent.
std::vector<formats::Section> radiance_sections(RadianceTableSet&& set);

// A read-only view of one kind's tables inside a list of sections (e.g. the pipeline artifact
// "section/tables"), with the same accessors as RadianceTableSet. Null pointers when absent.
struct RadianceSectionView {
  const reader::RadianceTableInfoRecord* info = nullptr;
  std::span<const uint32_t> clusters;
  std::span<const double> units;
  const std::byte* sat = nullptr;  // bins x N x N x clusters elements of info->element_bits
  bool present() const { return info != nullptr; }
};
RadianceSectionView find_radiance_sections(std::span<const formats::Section> sections,
                                           reader::RadianceTableKind kind);

}  // namespace clothbake::tables

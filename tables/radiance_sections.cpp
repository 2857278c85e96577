// Raw Integral-Radiance table sections (radiance_sections.hpp).
#include "tables/radiance_sections.hpp"

#include <cstring>

#include "common/error.hpp"

namespace clothbake::tables {

using reader::RadiancePart;
using reader::SectionType;

std::vector<formats::Section> radiance_sections(RadianceTableSet&& set) {
  std::vector<formats::Section> out;
  if (set.clusters.empty()) return out;
  const auto kind = set.kind();
  const uint32_t bins = uint32_t(set.bins()), n = set.info.resolution,
                 c = uint32_t(set.clusters.size());
  if (set.info.stored_clusters != c || set.units.size() != std::size_t(bins) * c ||
      set.sat.size() != set.element_count() * (set.info.element_bits / 8))
    throw_internal_error("radiance tables: inconsistent table set");
  const reader::RadianceTableInfoRecord info = set.info;
  out.push_back(formats::make_record_section<reader::RadianceTableInfoRecord>(
      SectionType::RadianceRawTables, reader::radiance_instance(kind, RadiancePart::Info),
      std::span<const reader::RadianceTableInfoRecord>(&info, 1)));
  out.push_back(formats::make_array_section<uint32_t>(
      SectionType::RadianceRawTables, reader::radiance_instance(kind, RadiancePart::Clusters),
      set.clusters, {c}));
  out.push_back(formats::make_array_section<double>(
      SectionType::RadianceRawTables, reader::radiance_instance(kind, RadiancePart::Units),
      set.units, {bins, c}));
  formats::Section sat;
  sat.type = SectionType::RadianceRawTables;
  sat.instance = reader::radiance_instance(kind, RadiancePart::Sat);
  sat.version = 1;
  sat.element = set.info.element_bits == 32 ? reader::ElementType::U32 : reader::ElementType::U64;
  sat.dims = {bins, n, n, c};
  sat.payload = std::move(set.sat);
  set.sat = {};
  out.push_back(std::move(sat));
  return out;
}

RadianceSectionView find_radiance_sections(std::span<const formats::Section> sections,
                                           reader::RadianceTableKind kind) {
  RadianceSectionView view;
  const formats::Section* parts[4] = {nullptr, nullptr, nullptr, nullptr};
  for (const auto& s : sections)
    for (uint32_t p = 0; p < 4; ++p)
      if (s.type == SectionType::RadianceRawTables &&
          s.instance == reader::radiance_instance(kind, RadiancePart(p)))
        parts[p] = &s;
  if (!parts[0] || !parts[1] || !parts[2] || !parts[3]) return view;
  // bytes(): a section from the stage cache may be mapped rather than owned (8-byte aligned).
  if (parts[0]->bytes().size() != sizeof(reader::RadianceTableInfoRecord))
    throw_internal_error("radiance tables: bad info section");
  view.info = reinterpret_cast<const reader::RadianceTableInfoRecord*>(parts[0]->bytes().data());
  view.clusters = {reinterpret_cast<const uint32_t*>(parts[1]->bytes().data()),
                   parts[1]->bytes().size() / 4};
  view.units = {reinterpret_cast<const double*>(parts[2]->bytes().data()),
                parts[2]->bytes().size() / 8};
  view.sat = parts[3]->bytes().data();
  return view;
}

}  // namespace clothbake::tables

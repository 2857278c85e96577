// docs/format.md against the code: every record table of the specification (marked
// `<!-- record: NAME SIZE -->`) lists exactly the fields of the C++ struct, in order, at their
// offsetof and with their sizeof; the section-type table names every type the reader knows, with
// its reader name and not as "reserved" (and an id the reader does not know only as "reserved");
// the element-type table matches element_type_name and element_size. So the document cannot
// drift from the layout silently, in either direction.
#include <gtest/gtest.h>

#include <cctype>
#include <cstddef>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "formats/reader/compressed_layout.hpp"
#include "formats/reader/layout.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/radiance_layout.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "model/asg.hpp"

namespace clothbake::reader {
namespace {

struct Field {
  std::string name;
  std::size_t offset = 0;
  std::size_t size = 0;
};

struct Record {
  std::size_t size = 0;
  std::vector<Field> fields;
};

#define CBK_FIELD(S, m)              \
  Field {                            \
#m, offsetof(S, m), sizeof(S::m) \
  }

// The layouts as the compiler sees them.
std::map<std::string, Record> code_records() {
  std::map<std::string, Record> r;
  r["FileHeader"] = {sizeof(FileHeader),
                     {CBK_FIELD(FileHeader, magic), CBK_FIELD(FileHeader, version_major),
                      CBK_FIELD(FileHeader, version_minor), CBK_FIELD(FileHeader, section_count),
                      CBK_FIELD(FileHeader, section_entry_size), CBK_FIELD(FileHeader, flags),
                      CBK_FIELD(FileHeader, file_size), CBK_FIELD(FileHeader, reserved),
                      CBK_FIELD(FileHeader, header_checksum)}};
  r["SectionEntry"] = {sizeof(SectionEntry),
                       {CBK_FIELD(SectionEntry, type), CBK_FIELD(SectionEntry, version),
                        CBK_FIELD(SectionEntry, codec), CBK_FIELD(SectionEntry, offset),
                        CBK_FIELD(SectionEntry, stored_size), CBK_FIELD(SectionEntry, checksum),
                        CBK_FIELD(SectionEntry, raw_size), CBK_FIELD(SectionEntry, element_type),
                        CBK_FIELD(SectionEntry, rank), CBK_FIELD(SectionEntry, dims),
                        CBK_FIELD(SectionEntry, instance)}};
  r["FabricInfoRecord"] = {
      sizeof(FabricInfoRecord),
      {CBK_FIELD(FabricInfoRecord, resolution), CBK_FIELD(FabricInfoRecord, yarn_count),
       CBK_FIELD(FabricInfoRecord, sheen_color), CBK_FIELD(FabricInfoRecord, sheen_roughness),
       CBK_FIELD(FabricInfoRecord, tile_size_mm), CBK_FIELD(FabricInfoRecord, reserved)}};
  r["YarnMaterialRecord"] = {
      sizeof(YarnMaterialRecord),
      {CBK_FIELD(YarnMaterialRecord, name), CBK_FIELD(YarnMaterialRecord, roughness),
       CBK_FIELD(YarnMaterialRecord, optical_thickness),
       CBK_FIELD(YarnMaterialRecord, specular_albedo),
       CBK_FIELD(YarnMaterialRecord, diffuse_reflectance),
       CBK_FIELD(YarnMaterialRecord, diffuse_transmittance), CBK_FIELD(YarnMaterialRecord, color),
       CBK_FIELD(YarnMaterialRecord, reserved)}};
  r["ParallaxInfoRecord"] = {
      sizeof(ParallaxInfoRecord),
      {CBK_FIELD(ParallaxInfoRecord, resolution), CBK_FIELD(ParallaxInfoRecord, dirs),
       CBK_FIELD(ParallaxInfoRecord, min_cos), CBK_FIELD(ParallaxInfoRecord, reference_height),
       CBK_FIELD(ParallaxInfoRecord, depth_scale),
       CBK_FIELD(ParallaxInfoRecord, max_quantization_error),
       CBK_FIELD(ParallaxInfoRecord, max_offset), CBK_FIELD(ParallaxInfoRecord, reserved)}};
  r["CompressedParallaxInfoRecord"] = {
      sizeof(CompressedParallaxInfoRecord),
      {CBK_FIELD(CompressedParallaxInfoRecord, resolution),
       CBK_FIELD(CompressedParallaxInfoRecord, dirs), CBK_FIELD(CompressedParallaxInfoRecord, bits),
       CBK_FIELD(CompressedParallaxInfoRecord, flags),
       CBK_FIELD(CompressedParallaxInfoRecord, min_cos),
       CBK_FIELD(CompressedParallaxInfoRecord, reference_height),
       CBK_FIELD(CompressedParallaxInfoRecord, max_offset),
       CBK_FIELD(CompressedParallaxInfoRecord, rms_offset_error),
       CBK_FIELD(CompressedParallaxInfoRecord, max_offset_error),
       CBK_FIELD(CompressedParallaxInfoRecord, max_depth_error)}};
  r["ScenePlanRecord"] = {
      sizeof(ScenePlanRecord),
      {CBK_FIELD(ScenePlanRecord, flags), CBK_FIELD(ScenePlanRecord, half_vector_bins_kept),
       CBK_FIELD(ScenePlanRecord, view_bins_kept), CBK_FIELD(ScenePlanRecord, reserved0),
       CBK_FIELD(ScenePlanRecord, scene_hash), CBK_FIELD(ScenePlanRecord, max_error),
       CBK_FIELD(ScenePlanRecord, reserved)}};
  r["VisibilityInfoRecord"] = {
      sizeof(VisibilityInfoRecord),
      {CBK_FIELD(VisibilityInfoRecord, resolution), CBK_FIELD(VisibilityInfoRecord, dirs),
       CBK_FIELD(VisibilityInfoRecord, normal_offset_texels),
       CBK_FIELD(VisibilityInfoRecord, max_bandwidth),
       CBK_FIELD(VisibilityInfoRecord, max_amplitude),
       CBK_FIELD(VisibilityInfoRecord, mean_fit_error),
       CBK_FIELD(VisibilityInfoRecord, max_fit_error), CBK_FIELD(VisibilityInfoRecord, reserved)}};
  r["AsgRecord"] = {sizeof(model::AsgRecord),
                    {CBK_FIELD(model::AsgRecord, axis_u), CBK_FIELD(model::AsgRecord, axis_v),
                     CBK_FIELD(model::AsgRecord, rotation), CBK_FIELD(model::AsgRecord, lambda),
                     CBK_FIELD(model::AsgRecord, mu), CBK_FIELD(model::AsgRecord, amplitude)}};
  r["RadianceTableInfoRecord"] = {
      sizeof(RadianceTableInfoRecord),
      {CBK_FIELD(RadianceTableInfoRecord, kind), CBK_FIELD(RadianceTableInfoRecord, resolution),
       CBK_FIELD(RadianceTableInfoRecord, bins_per_side),
       CBK_FIELD(RadianceTableInfoRecord, cluster_count),
       CBK_FIELD(RadianceTableInfoRecord, stored_clusters),
       CBK_FIELD(RadianceTableInfoRecord, element_bits),
       CBK_FIELD(RadianceTableInfoRecord, samples_per_bin_side),
       CBK_FIELD(RadianceTableInfoRecord, lobes), CBK_FIELD(RadianceTableInfoRecord, min_roughness),
       CBK_FIELD(RadianceTableInfoRecord, precision_target),
       CBK_FIELD(RadianceTableInfoRecord, reserved)}};
  r["CompressedTableInfoRecord"] = {
      sizeof(CompressedTableInfoRecord),
      {CBK_FIELD(CompressedTableInfoRecord, kind), CBK_FIELD(CompressedTableInfoRecord, resolution),
       CBK_FIELD(CompressedTableInfoRecord, bins_per_side),
       CBK_FIELD(CompressedTableInfoRecord, cluster_count),
       CBK_FIELD(CompressedTableInfoRecord, cell_count),
       CBK_FIELD(CompressedTableInfoRecord, image_count),
       CBK_FIELD(CompressedTableInfoRecord, coefficient_count),
       CBK_FIELD(CompressedTableInfoRecord, samples_per_bin_side),
       CBK_FIELD(CompressedTableInfoRecord, lobes), CBK_FIELD(CompressedTableInfoRecord, flags),
       CBK_FIELD(CompressedTableInfoRecord, min_roughness),
       CBK_FIELD(CompressedTableInfoRecord, bake_error),
       CBK_FIELD(CompressedTableInfoRecord, reserved)}};
  r["CompressedCell"] = {
      sizeof(CompressedCell),
      {CBK_FIELD(CompressedCell, cluster), CBK_FIELD(CompressedCell, rank),
       CBK_FIELD(CompressedCell, texels), CBK_FIELD(CompressedCell, first_image)}};
  return r;
}

#undef CBK_FIELD

std::vector<std::string> read_lines() {
  const std::string path = std::string(CLOTHBAKE_SOURCE_DIR) + "/docs/format.md";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  return lines;
}

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a])))
    ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1])))
    --b;
  return s.substr(a, b - a);
}

// Cells of a Markdown table row ("| a | b \| c |" -> {"a", "b \| c"}); empty unless a row.
std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  const std::string t = trim(line);
  if (t.size() < 2 || t.front() != '|') return out;
  std::string cell;
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (t[i] == '|' && t[i - 1] != '\\') {
      out.push_back(trim(cell));
      cell.clear();
    } else {
      cell += t[i];
    }
  }
  return out;
}

bool is_separator(const std::vector<std::string>& row) {
  for (const auto& c : row)
    if (c.find_first_not_of("-: ") != std::string::npos) return false;
  return !row.empty();
}

// Bytes of a doc type such as "u32", "f64[3]", "char[32]"; 0 if not understood.
std::size_t type_bytes(const std::string& type) {
  static const std::map<std::string, std::size_t> base = {
      {"u8", 1},  {"i8", 1},  {"char", 1}, {"u16", 2}, {"i16", 2}, {"f16", 2},
      {"u32", 4}, {"i32", 4}, {"f32", 4},  {"u64", 8}, {"i64", 8}, {"f64", 8}};
  const std::size_t bracket = type.find('[');
  const auto it = base.find(type.substr(0, bracket));
  if (it == base.end()) return 0;
  if (bracket == std::string::npos) return it->second;
  return it->second * std::size_t(std::stoul(type.substr(bracket + 1)));
}

std::string leading_identifier(const std::string& s) {
  std::size_t n = 0;
  while (n < s.size() && (std::isalnum(static_cast<unsigned char>(s[n])) || s[n] == '_'))
    ++n;
  return s.substr(0, n);
}

// Record tables of the document, by the name in their marker.
std::map<std::string, Record> doc_records(const std::vector<std::string>& lines) {
  std::map<std::string, Record> out;
  const std::string marker = "<!-- record:";
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string t = trim(lines[i]);
    if (t.rfind(marker, 0) != 0) continue;
    std::istringstream words(t.substr(marker.size()));
    std::string name;
    std::size_t size = 0;
    words >> name >> size;
    EXPECT_EQ(out.count(name), 0u) << "two tables for " << name;
    Record& r = out[name];
    r.size = size;
    std::size_t j = i + 1;
    const auto header = cells(j < lines.size() ? lines[j] : "");
    EXPECT_TRUE(header.size() >= 3 && header[0] == "offset" && header[1] == "type")
        << name << ": the marker must be followed by an 'offset | type | field' table";
    for (j += 2; j < lines.size(); ++j) {
      const auto row = cells(lines[j]);
      if (row.size() < 3) break;
      if (is_separator(row)) continue;
      Field f;
      f.offset = std::size_t(std::stoul(row[0]));
      f.size = type_bytes(row[1]);
      EXPECT_NE(f.size, 0u) << name << ": unknown type '" << row[1] << "'";
      f.name = leading_identifier(row[2]);
      r.fields.push_back(f);
    }
  }
  return out;
}

TEST(FormatDoc, EveryRecordTableMatchesTheStructFieldForField) {
  const auto lines = read_lines();
  const auto doc = doc_records(lines);
  const auto code = code_records();
  for (const auto& [name, expected] : code) {
    SCOPED_TRACE(name);
    const auto it = doc.find(name);
    ASSERT_NE(it, doc.end()) << "docs/format.md has no record table for " << name;
    const Record& got = it->second;
    EXPECT_EQ(got.size, expected.size) << "declared record size";
    ASSERT_EQ(got.fields.size(), expected.fields.size()) << "number of fields";
    std::size_t end = 0;
    for (std::size_t k = 0; k < expected.fields.size(); ++k) {
      const Field& e = expected.fields[k];
      const Field& g = got.fields[k];
      EXPECT_EQ(g.name, e.name) << "field " << k;
      EXPECT_EQ(g.offset, e.offset) << "offset of " << e.name;
      EXPECT_EQ(g.size, e.size) << "size of " << e.name;
      EXPECT_EQ(g.offset, end) << e.name << " does not follow the previous field (a hole?)";
      end = g.offset + g.size;
    }
    EXPECT_EQ(end, expected.size) << "the fields do not fill the record";
  }
  for (const auto& entry : doc)
    EXPECT_EQ(code.count(entry.first), 1u)
        << "docs/format.md has a record table for " << entry.first
        << " that this test does not know; add it to code_records()";
}

// Rows of the table that follows the first line starting with `heading`.
std::vector<std::vector<std::string>> table_after(const std::vector<std::string>& lines,
                                                  const std::string& heading) {
  std::vector<std::vector<std::string>> rows;
  std::size_t i = 0;
  while (i < lines.size() && lines[i].rfind(heading, 0) != 0)
    ++i;
  EXPECT_LT(i, lines.size()) << "no heading " << heading;
  while (i < lines.size() && cells(lines[i]).empty())
    ++i;
  for (; i < lines.size(); ++i) {
    auto row = cells(lines[i]);
    if (row.empty()) break;
    if (!is_separator(row)) rows.push_back(row);
  }
  if (!rows.empty()) rows.erase(rows.begin());  // the header row
  return rows;
}

TEST(FormatDoc, SectionTypeTableNamesEveryTypeTheReaderKnows) {
  const auto rows = table_after(read_lines(), "## 5. Section types");
  std::map<uint32_t, std::vector<std::string>> by_id;
  for (const auto& row : rows) {
    ASSERT_GE(row.size(), 4u) << row[0];
    const std::string& id = row[0];
    // Single ids only ("0x0502-0x05FF" ranges are reserved blocks).
    if (id.size() != 6 || id.rfind("0x", 0) != 0) continue;
    by_id[uint32_t(std::stoul(id.substr(2), nullptr, 16))] = row;
  }
  int known = 0;
  for (uint32_t type = 0; type <= 0xFFFF; ++type) {
    const char* name = section_type_name(SectionType(type));
    const auto it = by_id.find(type);
    if (name == nullptr) {
      // A row for an id the reader does not know can only announce a reserved id.
      if (it != by_id.end() && it->second[2].rfind("reserved", 0) != 0)
        ADD_FAILURE() << "docs/format.md lists type " << it->second[0] << " ('" << it->second[1]
                      << "') as written, but the reader does not know it";
      continue;
    }
    ++known;
    ASSERT_NE(it, by_id.end()) << "docs/format.md has no row for type " << name;
    EXPECT_EQ(it->second[1], name) << "name of type " << it->second[0];
    EXPECT_NE(it->second[2].rfind("reserved", 0), 0u)
        << "type " << name << " is written but its row says '" << it->second[2] << "'";
  }
  EXPECT_GE(known, 17);
}

TEST(FormatDoc, ElementTypeTableMatchesTheReader) {
  const auto rows = table_after(read_lines(), "## 4. Typed-array payloads");
  int seen = 0;
  for (const auto& row : rows)
    for (std::size_t c = 0; c + 2 < row.size(); c += 4) {  // "id | name | bytes |  |" blocks
      if (row[c].empty()) continue;
      const auto type = ElementType(std::stoul(row[c]));
      SCOPED_TRACE(row[c]);
      ASSERT_NE(element_type_name(type), nullptr);
      EXPECT_EQ(row[c + 1], element_type_name(type));
      const std::string bytes = row[c + 2];
      EXPECT_EQ(bytes == "—" ? 0u : uint32_t(std::stoul(bytes)), element_size(type));
      ++seen;
    }
  EXPECT_EQ(seen, 12);
}

}  // namespace
}  // namespace clothbake::reader

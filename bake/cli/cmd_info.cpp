// clothbake info ASSET [--json]: what an asset holds: format version, size, content hash, every
// section (type, instance, version, element type, shape, bytes), the fabric records and the
// metadata (tool, bake parameters, inputs with their hashes, stages). Checks the structure and
// the header checksum only (`clothbake validate` checks everything). Exit 3 if the asset does not
// open, 2 if the file cannot be read.
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <fmt/format.h>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/memory_estimate.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/writer/metadata_json.hpp"
#include "formats/writer/open_asset.hpp"

namespace clothbake::cli {
namespace {

using namespace clothbake::reader;

std::string hex(uint64_t value, int digits) {
  std::ostringstream out;
  out << std::hex << std::setw(digits) << std::setfill('0') << value;
  return out.str();
}

std::string section_name(const SectionInfo& s) {
  const char* name = section_type_name(s.type);
  return name ? name : "0x" + hex(uint32_t(s.type), 4);
}

// One section table entry as JSON (the elements of info --json's "sections" array).
nlohmann::json section_json(const Asset& asset, uint32_t index) {
  SectionInfo s;
  (void)asset.section(index, &s);
  const char* element = element_type_name(s.element_type);
  const char* codec = codec_name(s.codec);
  return {{"index", index},
          {"name", section_name(s)},
          {"type", uint32_t(s.type)},
          {"instance", s.instance},
          {"version", s.version},
          {"codec", codec ? codec : "unknown"},
          {"element", element ? element : "unknown"},
          {"dims", std::vector<uint32_t>(s.dims, s.dims + s.rank)},
          {"offset", s.offset},
          {"bytes", s.stored_size},
          {"xxh64", hex(s.checksum, 16)}};
}

// Everything info reports except the per-section list, which callers stream from the asset's
// table (an asset may hold the format's maximum of 2^20 sections: as one JSON tree they took
// 3.2 GB and 14 s). "sections" is an empty placeholder array.
nlohmann::json info_json(const std::string& path, const Asset& asset) {
  nlohmann::json doc;
  doc["path"] = path;
  doc["format"] = {{"major", asset.version_major()}, {"minor", asset.version_minor()}};
  doc["size_bytes"] = asset.file_size();
  doc["content_hash"] = hex(asset.content_hash(), 16);
  doc["sections"] = nlohmann::json::array();
  // Bytes per section name (a handful of names, whatever the section count).
  std::map<std::string, uint64_t> bytes_by_name;
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    SectionInfo s;
    (void)asset.section(i, &s);
    bytes_by_name[section_name(s)] += s.stored_size;
  }
  const FabricInfoRecord* fabric = nullptr;
  if (read_fabric_info(asset, &fabric).ok())
    doc["fabric_info"] = {{"resolution", fabric->resolution},
                          {"yarn_count", fabric->yarn_count},
                          {"tile_size_mm", fabric->tile_size_mm},
                          {"sheen_color", fabric->sheen_color},
                          {"sheen_roughness", fabric->sheen_roughness}};
  ArrayView<YarnMaterialRecord> yarns;
  if (read_yarn_materials(asset, &yarns).ok()) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& y : yarns)
      list.push_back({{"name", std::string(y.name, strnlen(y.name, sizeof y.name))},
                      {"roughness", y.roughness},
                      {"optical_thickness", y.optical_thickness},
                      {"specular_albedo", y.specular_albedo},
                      {"diffuse_reflectance", y.diffuse_reflectance},
                      {"diffuse_transmittance", y.diffuse_transmittance},
                      {"color", y.color}});
    doc["yarns"] = list;
  }
  // Metadata over the limits, not JSON or with a known key of the wrong type: exit 3 (CBK-E020,
  // CBK-E023), as validate reports it.
  doc["metadata"] = formats::read_metadata(asset);
  // Bytes per section name, and what the asset would weigh with the raw forms of the compressed
  // sections instead (from the sizes the parallax and compress stages recorded in the metadata).
  nlohmann::json by_name(bytes_by_name);
  int64_t raw_total = int64_t(asset.file_size());
  // The recorded sizes are information: a value of an unexpected type leaves the total as the
  // file's size instead of failing the command.
  try {
    const nlohmann::json* params = nullptr;
    if (doc.contains("metadata") && doc["metadata"].is_object() &&
        doc["metadata"].contains("parameters"))
      params = &doc["metadata"]["parameters"];
    if (params && by_name.contains("parallax_entropy") && !by_name.contains("parallax") &&
        params->contains("parallax") && (*params)["parallax"].contains("compressed"))
      raw_total += int64_t((*params)["parallax"]["compressed"].value("raw_bytes", uint64_t(0))) -
                   int64_t(by_name["parallax_entropy"].get<uint64_t>());
    if (params && by_name.contains("radiance_compressed") && !by_name.contains("radiance_tables") &&
        params->contains("compress") && (*params)["compress"].contains("kinds")) {
      raw_total -= int64_t(by_name["radiance_compressed"].get<uint64_t>());
      for (const auto& k : (*params)["compress"]["kinds"])
        raw_total += int64_t(k.value("raw_float_bytes", uint64_t(0)));
    }
  } catch (const nlohmann::json::exception&) {
    raw_total = int64_t(asset.file_size());
  }
  // A scene-planned asset: what its bake left out, from the binary record (the
  // metadata's words when present).
  ScenePlanRecord plan{};
  bool planned = false;
  if (read_scene_plan(asset, &plan, &planned).ok() && planned) {
    nlohmann::json p = {{"transmission_left_out", (plan.flags & kPlanNoTransmission) != 0},
                        {"half_vector_bins_kept", plan.half_vector_bins_kept},
                        {"view_bins_kept", plan.view_bins_kept},
                        {"scene_xxh64", pipeline::hex64(plan.scene_hash)},
                        {"max_error", plan.max_error},
                        {"left_out", nlohmann::json::array()}};
    try {
      const auto& m = doc["metadata"];
      if (m.is_object() && m.contains("parameters") && m["parameters"].contains("scene_plan")) {
        const auto& sp = m["parameters"]["scene_plan"];
        p["scene"] = sp.value("scene", "");
        if (sp.contains("left_out") && sp["left_out"].is_array()) p["left_out"] = sp["left_out"];
      }
    } catch (const nlohmann::json::exception&) {
    }
    doc["scene_plan"] = p;
  }
  doc["sizes"] = {{"by_name", by_name},
                  {"total_bytes", asset.file_size()},
                  {"raw_forms_total_bytes", raw_total}};
  return doc;
}

void print_text(const nlohmann::json& doc, const Asset& asset) {
  std::ostream& out = std::cout;
  // Names and paths come from the asset: escape what a terminal would interpret.
  auto text = [](const nlohmann::json& value) { return terminal_safe(value.get<std::string>()); };
  out << "asset:    " << text(doc["path"]) << '\n';
  out << "format:   " << doc["format"]["major"] << '.' << doc["format"]["minor"] << '\n';
  out << "size:     " << stages::format_bytes(doc["size_bytes"].get<double>()) << " ("
      << doc["size_bytes"] << " bytes)\n";
  out << "content:  xxh64 " << doc["content_hash"].get<std::string>() << '\n';
  if (doc.contains("metadata") && doc["metadata"].is_object()) {
    const auto& m = doc["metadata"];
    if (m.contains("tool"))
      out << "tool:     " << terminal_safe(m["tool"].value("name", "?")) << ' '
          << terminal_safe(m["tool"].value("version", "?")) << '\n';
    if (m.contains("stages")) {
      out << "stages:  ";
      for (const auto& s : m["stages"])
        out << ' ' << text(s);
      out << '\n';
    }
    if (m.contains("fabric") && m["fabric"].contains("inputs")) {
      out << "inputs:\n";
      for (const auto& in : m["fabric"]["inputs"])
        out << "  " << std::left << std::setw(10) << terminal_safe(in.value("role", "")) << ' '
            << terminal_safe(in.value("xxh64", "")) << "  " << terminal_safe(in.value("path", ""))
            << '\n';
    }
    if (m.contains("fabric") && m["fabric"].is_object() && m["fabric"].contains("name") &&
        m["fabric"]["name"].is_string())
      out << "name:     " << text(m["fabric"]["name"]) << '\n';
    if (m.contains("fabric") && m["fabric"].contains("bake") && m["fabric"]["bake"].is_object()) {
      // One "key value" per setting, a line of them at a time (the JSON has them typed).
      out << "bake:     ";
      int on_line = 0;
      for (const auto& [key, value] : m["fabric"]["bake"].items()) {
        if (on_line == 4) {
          out << "\n          ";
          on_line = 0;
        } else if (on_line > 0) {
          out << ", ";
        }
        out << terminal_safe(key) << ' '
            << terminal_safe(
                   value.is_string()
                       ? value.get<std::string>()
                       : value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
        ++on_line;
      }
      out << '\n';
    }
  }
  if (doc.contains("fabric_info")) {
    const auto& f = doc["fabric_info"];
    out << "fabric:   " << f["resolution"] << " x " << f["resolution"] << " texels, "
        << f["yarn_count"] << " yarns, tile "
        << (f["tile_size_mm"].is_number() ? fmt::format("{:.6g}", f["tile_size_mm"].get<double>())
                                          : std::string("?"))
        << " mm\n";
  }
  auto rgb = [](const nlohmann::json& c) {
    if (!c.is_array() || c.size() != 3 || !c[0].is_number() || !c[1].is_number() ||
        !c[2].is_number())
      return std::string("?");
    return fmt::format("({:.3g}, {:.3g}, {:.3g})", c[0].get<double>(), c[1].get<double>(),
                       c[2].get<double>());
  };
  if (doc.contains("fabric_info") && doc["fabric_info"].contains("sheen_color"))
    out << "  sheen colour " << rgb(doc["fabric_info"]["sheen_color"]) << ", roughness "
        << doc["fabric_info"]["sheen_roughness"] << '\n';
  if (doc.contains("yarns"))
    for (const auto& y : doc["yarns"])
      out << "  yarn " << std::left << std::setw(12) << text(y["name"]) << " colour "
          << rgb(y.value("color", nlohmann::json())) << ", roughness " << y["roughness"]
          << ", optical thickness " << y["optical_thickness"] << '\n';
  if (doc.contains("scene_plan")) {
    const auto& p = doc["scene_plan"];
    out << "plan:     scene " << terminal_safe(p.value("scene", std::string("?"))) << " (xxh64 "
        << p["scene_xxh64"].get<std::string>() << "), error budget " << p["max_error"] << '\n';
    if (p["left_out"].empty()) out << "  nothing left out\n";
    for (const auto& what : p["left_out"])
      out << "  left out: " << (what.is_string() ? terminal_safe(what.get<std::string>()) : "?")
          << '\n';
  }
  out << "sections: " << asset.section_count() << '\n';
  out << "  " << std::left << std::setw(4) << "#" << std::setw(26) << "name" << std::setw(6)
      << "inst" << std::setw(5) << "ver" << std::setw(6) << "type" << std::setw(18) << "shape"
      << std::right << std::setw(12) << "bytes" << '\n';
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    SectionInfo s;
    (void)asset.section(i, &s);
    std::string shape;
    for (uint32_t d = 0; d < s.rank; ++d) {
      if (!shape.empty()) shape += 'x';
      shape += std::to_string(s.dims[d]);
    }
    const char* element = element_type_name(s.element_type);
    out << "  " << std::left << std::setw(4) << i << std::setw(26) << section_name(s)
        << std::setw(6) << s.instance << std::setw(5) << int(s.version) << std::setw(6)
        << (element ? element : "unknown") << std::setw(18) << (shape.empty() ? "-" : shape)
        << std::right << std::setw(12) << s.stored_size << '\n';
  }
  const auto& sizes = doc["sizes"];
  const double total = double(sizes["total_bytes"].get<uint64_t>());
  out << "sizes:    per section name (share of the file)\n";
  for (const auto& [name, bytes] : sizes["by_name"].items())
    out << "  " << std::left << std::setw(26) << name << std::right << std::setw(12)
        << bytes.get<uint64_t>() << std::setw(8) << std::fixed << std::setprecision(1)
        << (total > 0 ? 100.0 * double(bytes.get<uint64_t>()) / total : 0.0) << " %\n";
  out << std::defaultfloat << "  total " << sizes["total_bytes"].get<uint64_t>()
      << " bytes; with the raw forms of its compressed sections "
      << sizes["raw_forms_total_bytes"].get<int64_t>() << " bytes\n";
  out.flush();
}

// print_json(doc) with doc's empty "sections" placeholder replaced by the asset's section table,
// written one entry at a time: the same bytes as one JSON tree, in memory bounded by one entry.
void print_json_with_sections(const nlohmann::json& doc, const Asset& asset) {
  auto dump = [](const nlohmann::json& value) {
    return value.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
  };
  const std::string text = dump(doc);
  // The top-level key is the only one at an indent of two spaces; newlines inside strings are
  // escaped, so this is found exactly once.
  const std::string placeholder = "\n  \"sections\": []";
  const size_t at = text.find(placeholder);
  if (at == std::string::npos || asset.section_count() == 0) {
    print_json(doc);
    return;
  }
  std::ostream& out = std::cout;
  out.write(text.data(), std::streamsize(at));
  out << "\n  \"sections\": [";
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    std::string entry = dump(section_json(asset, i));
    out << (i ? ",\n    " : "\n    ");
    for (char c : entry) {
      out.put(c);
      if (c == '\n') out << "    ";
    }
  }
  out << "\n  ]";
  const size_t rest = at + placeholder.size();
  out.write(text.data() + rest, std::streamsize(text.size() - rest));
  out << '\n';
  out.flush();
}

Action setup_info(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  add_asset_argument(app, *path);
  add_json_flag(app, *json);
  return [path, json] {
    // The structure and the header checksum (which covers the table, hence every section's
    // checksum that info prints); not every payload, so that damaged assets can be described.
    const Asset asset = formats::open_asset(*path, formats::Verify::Structure);
    formats::throw_if_failed(reader::verify_header_checksum(asset), *path);
    const nlohmann::json doc = info_json(*path, asset);
    if (*json)
      print_json_with_sections(doc, asset);
    else
      print_text(doc, asset);
    return 0;
  };
}

const bool info_registered = register_command(
    {"info", "Describe an asset: sections, sizes, parameters and provenance", setup_info});

}  // namespace
}  // namespace clothbake::cli

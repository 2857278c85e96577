// Metadata parsing and schema checks (metadata_json.hpp).
#include "formats/writer/metadata_json.hpp"

#include "common/error.hpp"
#include "formats/validate/metadata_limits.hpp"

namespace clothbake::formats {
namespace {

using nlohmann::json;
using reader::Check;

using Type = bool (json::*)() const noexcept;

const char* type_name(Type type) {
  if (type == &json::is_string) return "a string";
  if (type == &json::is_number) return "a number";
  if (type == &json::is_object) return "an object";
  if (type == &json::is_array) return "an array";
  return "of another type";
}

class SchemaChecker {
 public:
  explicit SchemaChecker(std::vector<MetadataFinding>& findings) : findings_(findings) {}

  // Reports `key` of `object` when present with another type; returns whether it is there and
  // of the right type.
  bool expect(const json& object, const std::string& where, const char* key, Type type) {
    const auto it = object.find(key);
    if (it == object.end()) return false;
    if (((*it).*type)()) return true;
    findings_.push_back({Check::MetadataSchema, "metadata: \"" + where + key + "\" is not " +
                                                    std::string(type_name(type))});
    return false;
  }
  // Every element of object[key] (an array) has `type`.
  void expect_elements(const json& object, const std::string& where, const char* key, Type type) {
    if (!expect(object, where, key, &json::is_array)) return;
    const json& list = object[key];
    for (std::size_t i = 0; i < list.size(); ++i)
      if (!(list[i].*type)()) {
        findings_.push_back({Check::MetadataSchema, "metadata: \"" + where + key + "[" +
                                                        std::to_string(i) + "]\" is not " +
                                                        std::string(type_name(type))});
        return;
      }
  }

 private:
  std::vector<MetadataFinding>& findings_;
};

void check_schema(const json& m, std::vector<MetadataFinding>& findings) {
  SchemaChecker c(findings);
  c.expect(m, "", "format_version", &json::is_string);
  if (c.expect(m, "", "tool", &json::is_object)) {
    c.expect(m["tool"], "tool.", "name", &json::is_string);
    c.expect(m["tool"], "tool.", "version", &json::is_string);
  }
  c.expect_elements(m, "", "stages", &json::is_string);
  c.expect(m, "", "parameters", &json::is_object);
  c.expect_elements(m, "", "timings", &json::is_object);
  if (c.expect(m, "", "fabric", &json::is_object)) {
    const json& f = m["fabric"];
    c.expect(f, "fabric.", "name", &json::is_string);
    c.expect(f, "fabric.", "resolution", &json::is_number);
    c.expect(f, "fabric.", "tile_size_mm", &json::is_number);
    c.expect_elements(f, "fabric.", "yarns", &json::is_string);
    c.expect(f, "fabric.", "sheen", &json::is_object);
    c.expect(f, "fabric.", "bake", &json::is_object);
    c.expect_elements(f, "fabric.", "inputs", &json::is_object);
    if (f.contains("inputs") && f["inputs"].is_array())
      for (std::size_t i = 0; i < f["inputs"].size(); ++i) {
        const std::string where = "fabric.inputs[" + std::to_string(i) + "].";
        for (const char* key : {"role", "path", "xxh64"})
          c.expect(f["inputs"][i], where, key, &json::is_string);
      }
  }
}

}  // namespace

std::vector<MetadataFinding> check_metadata(const reader::Asset& asset, json* out) {
  std::vector<MetadataFinding> findings;
  *out = json();
  std::string_view text;
  const reader::Status status = asset.metadata_json(&text);
  if (!status.ok()) {
    findings.push_back(
        {status.code() == reader::ErrorCode::NotFound ? Check::MissingSection : status.check(),
         std::string("metadata: ") + status.message()});
    return findings;
  }
  return check_metadata_text(text, out);
}

std::vector<MetadataFinding> check_metadata_text(std::string_view text, json* out) {
  std::vector<MetadataFinding> findings;
  *out = json();
  const reader::Status limits = reader::check_metadata_limits(text);
  if (!limits.ok()) {
    findings.push_back({Check::Metadata, limits.message()});
    return findings;
  }
  json metadata = json::parse(text, nullptr, false);
  if (metadata.is_discarded() || !metadata.is_object()) {
    findings.push_back({Check::Metadata, "metadata: not valid JSON"});
    return findings;
  }
  const auto format = metadata.find("format");
  if (format == metadata.end() || !format->is_string() || *format != "clothbake-asset")
    findings.push_back({Check::Metadata, "metadata: \"format\" is not \"clothbake-asset\""});
  check_schema(metadata, findings);
  *out = std::move(metadata);
  return findings;
}

json read_metadata(const reader::Asset& asset) {
  json metadata;
  const auto findings = check_metadata(asset, &metadata);
  if (!findings.empty())
    throw Error(ExitCode::InvalidAsset, std::string(reader::check_id(findings.front().check)) +
                                            ": " + findings.front().message);
  return metadata;
}

}  // namespace clothbake::formats

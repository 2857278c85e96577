// Batch stamps (batch_stamp.hpp).
#include "bake/cli/batch_stamp.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdint>
#include <exception>
#include <stdexcept>

#include "bake/inputs/fabric_files.hpp"
#include "common/error.hpp"
#include "formats/validate/metadata_limits.hpp"

namespace clothbake::cli {
namespace {

int64_t mtime_ns(const struct stat& st) {
  return int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
}

// Paths are bytes and stamps are JSON: a path that is not UTF-8 (or that starts with "hex:") is
// kept as "hex:" and its bytes in hex, so that it reads back exactly.
std::string stamp_text(const std::string& path) {
  if (reader::utf8_error_offset(path) == path.size() && path.rfind("hex:", 0) != 0) return path;
  std::string out = "hex:";
  for (unsigned char c : path)
    out += fmt::format("{:02x}", c);
  return out;
}

std::string stamp_path(const std::string& text) {
  if (text.rfind("hex:", 0) != 0) return text;
  std::string out;
  for (std::size_t i = 4; i + 1 < text.size(); i += 2)
    out += char(std::stoi(text.substr(i, 2), nullptr, 16));  // throws on a non-hex digit
  return out;
}

}  // namespace

uint64_t json_unsigned(const nlohmann::json& value, const char* what) {
  if (value.is_number_unsigned()) return value.get<uint64_t>();
  if (value.is_number_integer() && value.get<int64_t>() >= 0) return uint64_t(value.get<int64_t>());
  throw std::invalid_argument(std::string(what) + " is not a whole number >= 0 below 2^64");
}

int64_t json_signed(const nlohmann::json& value, const char* what) {
  if (value.is_number_integer() && !value.is_number_unsigned()) return value.get<int64_t>();
  if (value.is_number_unsigned() && value.get<uint64_t>() <= uint64_t(INT64_MAX))
    return int64_t(value.get<uint64_t>());
  throw std::invalid_argument(std::string(what) + " is not a whole number below 2^63 in magnitude");
}

namespace {

// check_stamp on a stamp that parsed; throws (nlohmann::json::exception, std::exception) on
// values of the wrong types.
StampCheck check_parsed(const nlohmann::json& stamp, const StampKey& key) {
  StampCheck out;
  out.peak_rss_bytes = stamp.contains("peak_rss_bytes")
                           ? json_unsigned(stamp["peak_rss_bytes"], "peak_rss_bytes")
                           : 0;
  if (stamp.value("tool", "") != key.tool || stamp.value("exe", "") != stamp_text(key.exe)) {
    out.why = "another clothbake";
    return out;
  }
  if (stamp.value("options", "") != stamp_text(key.options) ||
      stamp.value("fabric", "") != stamp_text(key.fabric)) {
    out.why = "other options";
    return out;
  }
  struct stat st {};
  if (::stat(key.output.c_str(), &st) != 0 ||
      uint64_t(st.st_size) != json_unsigned(stamp.at("output").at("size"), "output.size") ||
      mtime_ns(st) != json_signed(stamp.at("output").at("mtime_ns"), "output.mtime_ns")) {
    out.why = "output missing or changed";
    return out;
  }
  const uint64_t output_size = uint64_t(st.st_size);
  for (const auto& input : stamp.at("inputs")) {
    const std::string path = stamp_path(input.at("path").get<std::string>());
    if (::stat(path.c_str(), &st) != 0) {
      out.why = path + " is gone";
      return out;
    }
    const bool same_size = uint64_t(st.st_size) == json_unsigned(input.at("size"), "size");
    if (same_size && mtime_ns(st) == json_signed(input.at("mtime_ns"), "mtime_ns")) continue;
    // Touched: the content decides (another size is another content, no need to read it).
    std::string hash;
    if (same_size) try {
        hash = inputs::hash_file(path, path);
      } catch (const Error&) {
      }
    if (hash.empty() || hash != input.at("xxh64").get<std::string>()) {
      out.why = path + " changed";
      return out;
    }
  }
  out.up_to_date = true;
  out.output_size = output_size;
  return out;
}

}  // namespace

StampCheck check_stamp(std::string_view text, const StampKey& key) {
  try {
    return check_parsed(nlohmann::json::parse(text), key);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception&) {
    StampCheck out;
    out.why = "unreadable stamp";
    return out;
  }
}

std::string make_stamp(const StampKey& key, const std::string& scene,
                       const nlohmann::json& report) {
  nlohmann::json stamp;
  stamp["tool"] = key.tool;
  stamp["exe"] = stamp_text(key.exe);
  stamp["options"] = stamp_text(key.options);
  stamp["fabric"] = stamp_text(key.fabric);
  stamp["peak_rss_bytes"] = report.at("total").at("peak_rss_bytes");
  stamp["seconds"] = report.at("total").at("wall_seconds");
  struct stat st {};
  ::stat(key.output.c_str(), &st);
  stamp["output"] = {{"size", uint64_t(st.st_size)}, {"mtime_ns", mtime_ns(st)}};
  nlohmann::json files = nlohmann::json::array();
  for (const auto& input : report.at("inputs")) {
    const std::string role = input.value("role", "");
    const std::string path = role == "fabric" ? key.fabric
                             : role == "scene" && !scene.empty()
                                 ? scene
                                 : input.at("path").get<std::string>();
    struct stat ist {};
    ::stat(path.c_str(), &ist);
    files.push_back({{"path", stamp_text(path)},
                     {"size", uint64_t(ist.st_size)},
                     {"mtime_ns", mtime_ns(ist)},
                     {"xxh64", input.at("xxh64")}});
  }
  stamp["inputs"] = files;
  return stamp.dump(1) + "\n";
}

}  // namespace clothbake::cli

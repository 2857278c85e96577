// Sniffing the kind of an input file (input_kind.hpp).
#include "bake/inputs/input_kind.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "common/error.hpp"
#include "formats/reader/layout.hpp"

namespace clothbake::inputs {
namespace {

bool starts_with_header(std::string_view line, std::string_view header) {
  if (line.size() < header.size()) return false;
  for (std::size_t k = 0; k < header.size(); ++k)
    if (std::tolower(static_cast<unsigned char>(line[k])) !=
        std::tolower(static_cast<unsigned char>(header[k])))
      return false;
  // "[bake]" but not "[bakery]": the header ends, or continues as a sub-table ("[weave.warp]").
  return line.size() == header.size() || header.back() != ']' || line[header.size()] == ' ' ||
         line[header.size()] == '\t' || line[header.size()] == '#' || line[header.size()] == '\r';
}

}  // namespace

const char* input_kind_name(InputKind kind) {
  switch (kind) {
    case InputKind::Fabric:
      return "fabric description";
    case InputKind::Scene:
      return "scene";
    case InputKind::Wif:
      return "WIF draft";
    case InputKind::Asset:
      return "clothbake asset";
    case InputKind::Unknown:
      break;
  }
  return "file of another kind";
}

InputKind sniff_input_kind(std::string_view bytes) {
  if (bytes.size() >= sizeof reader::kMagic &&
      std::memcmp(bytes.data(), reader::kMagic, sizeof reader::kMagic) == 0)
    return InputKind::Asset;
  static constexpr std::string_view kScene[] = {"[camera]", "[[light]]", "[[object]]", "[render]"};
  static constexpr std::string_view kFabric[] = {"[maps]", "[weave]", "[weave.", "[[yarn]]",
                                                 "[tile]", "[sheen]", "[bake]"};
  bool scene = false, fabric = false, wif = false;
  std::size_t start = 0;
  while (start < bytes.size()) {
    std::size_t end = bytes.find('\n', start);
    if (end == std::string_view::npos) end = bytes.size();
    std::string_view line = bytes.substr(start, end - start);
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t'))
      line.remove_prefix(1);
    if (!line.empty() && line.front() == '[') {
      wif = wif || starts_with_header(line, "[WIF]");
      for (std::string_view h : kScene)
        scene = scene || starts_with_header(line, h);
      for (std::string_view h : kFabric)
        fabric = fabric || starts_with_header(line, h);
    }
    start = end + 1;
  }
  if (wif) return InputKind::Wif;
  if (scene != fabric) return scene ? InputKind::Scene : InputKind::Fabric;
  return InputKind::Unknown;
}

void require_input_kind(InputKind kind, const std::string& path, InputKind expected,
                        const std::string& needs) {
  if (kind == InputKind::Unknown || kind == expected) return;
  throw_input_error(path + " is a " + input_kind_name(kind) + ", not a " +
                    input_kind_name(expected) + ": " + needs);
}

}  // namespace clothbake::inputs

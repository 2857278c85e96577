// Names of the Integral-Radiance table kinds and the lobe -> table mapping (radiance_layout.hpp).
#include <cstring>

#include "formats/reader/radiance_layout.hpp"

namespace clothbake::reader {

const char* radiance_kind_name(RadianceTableKind kind) noexcept {
  switch (kind) {
    case RadianceTableKind::Specular:
      return "specular";
    case RadianceTableKind::Gap:
      return "gap";
  }
  return nullptr;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
bool radiance_kind_of_lobe(const char* lobe_name, RadianceTableKind* out) noexcept {
  if (lobe_name == nullptr || out == nullptr) return false;
  if (std::strcmp(lobe_name, "specular_reflection") == 0 ||
      std::strcmp(lobe_name, "specular_transmission") == 0) {
    *out = RadianceTableKind::Specular;
    return true;
  }
  if (std::strcmp(lobe_name, "delta_transmission") == 0) {
    *out = RadianceTableKind::Gap;
    return true;
  }
  return false;
}
#endif

}  // namespace clothbake::reader

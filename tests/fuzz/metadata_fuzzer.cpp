// libFuzzer harness of the metadata parser (formats/writer/metadata_json.hpp): any bytes as the
// metadata text must give findings or a parsed object, never a crash, a stack overflow (nesting is
// bounded before nlohmann parses) or an exception; an accepted document re-serialises without
// throwing (invalid UTF-8 replaced). Built with -fsanitize=fuzzer,address,undefined.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "formats/validate/metadata_limits.hpp"
#include "formats/writer/metadata_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  (void)clothbake::reader::utf8_error_offset(text);
  nlohmann::json metadata;
  const auto findings = clothbake::formats::check_metadata_text(text, &metadata);
  if (findings.empty() && !metadata.is_object()) __builtin_trap();
  if (!metadata.is_null())
    (void)metadata.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
  return 0;
}

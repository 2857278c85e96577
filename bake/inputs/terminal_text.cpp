// Terminal-safe text (terminal_text.hpp).
#include "bake/inputs/terminal_text.hpp"

#include <cstdio>

#include "formats/validate/metadata_limits.hpp"

namespace clothbake {

namespace {

std::string escaped(std::string_view text, bool keep_newlines) {
  std::string out;
  out.reserve(text.size());
  auto escape = [&out](unsigned char byte) {
    char hex[5];
    std::snprintf(hex, sizeof hex, "\\x%02X", unsigned(byte));
    out += hex;
  };
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      if ((c < 0x20 || c == 0x7f) && !(keep_newlines && c == '\n'))
        escape(c);
      else
        out += char(c);
      ++i;
      continue;
    }
    // The longest valid UTF-8 sequence starting here (1 to 4 bytes), if any.
    std::size_t len = (c & 0xe0) == 0xc0 ? 2 : (c & 0xf0) == 0xe0 ? 3 : (c & 0xf8) == 0xf0 ? 4 : 0;
    if (len == 0 || i + len > text.size() ||
        reader::utf8_error_offset(text.substr(i, len)) != len) {
      escape(c);
      ++i;
      continue;
    }
    // U+0080-U+009F (C1 controls) are 0xC2 0x80-0x9F.
    if (c == 0xc2 && static_cast<unsigned char>(text[i + 1]) < 0xa0) {
      escape(c);
      escape(static_cast<unsigned char>(text[i + 1]));
    } else {
      out.append(text.substr(i, len));
    }
    i += len;
  }
  return out;
}

}  // namespace

std::string terminal_safe(std::string_view text) {
  return escaped(text, false);
}

std::string terminal_safe_lines(std::string_view text) {
  return escaped(text, true);
}

}  // namespace clothbake

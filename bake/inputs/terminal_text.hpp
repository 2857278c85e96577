// Text from an asset or an input file, made safe to print on a terminal.
#pragma once

#include <string>
#include <string_view>

namespace clothbake {

// `text` with every byte a terminal could interpret escaped: C0 controls (ESC, CR, BS...), DEL,
// C1 controls (U+0080-U+009F) and bytes that are not valid UTF-8 become "\xHH" (one per byte);
// a backslash stays as is. Valid printable UTF-8 passes unchanged.
std::string terminal_safe(std::string_view text);

// terminal_safe for text of several lines: the same, except that a line feed stays one.
std::string terminal_safe_lines(std::string_view text);

}  // namespace clothbake

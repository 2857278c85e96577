// Limits on the metadata JSON that a reader checks before any JSON parser sees it (docs/format.md,
// §6.1 and check CBK-E020): a recursive parser on hostile nesting overflows the stack, and
// pretty-printing deep nesting grows quadratically. C++17, standard library only.
#pragma once

#include <cstddef>
#include <string_view>

#include "formats/reader/status.hpp"

namespace clothbake::reader {

// Deepest nesting of arrays and objects accepted in the metadata (clothbake writes at most 6).
inline constexpr std::size_t kMaxMetadataDepth = 64;
// Largest metadata section accepted, in bytes (clothbake writes a few kilobytes).
inline constexpr std::size_t kMaxMetadataBytes = std::size_t(16) << 20;

// Ok when `text` is at most kMaxMetadataBytes long and no '[' or '{' outside a JSON string opens a
// level deeper than kMaxMetadataDepth; otherwise Malformed with Check::Metadata, naming the byte
// offset. Linear time, constant memory, no recursion; does not otherwise check the JSON syntax.
Status check_metadata_limits(std::string_view text) noexcept;

// The offset of the first byte of `text` that is not part of a valid UTF-8 sequence (overlongs,
// surrogates and code points past U+10FFFF are invalid), or text.size() when it is all valid.
std::size_t utf8_error_offset(std::string_view text) noexcept;

}  // namespace clothbake::reader

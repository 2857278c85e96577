#include "formats/reader/status.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace clothbake::reader {

const char* check_id(Check check) noexcept {
  // Static table of "CBK-E001".."CBK-E099" / "CBK-W001".."CBK-W099" strings, filled once.
  static char ids[2][100][9];
  static const bool filled = [] {
    for (int kind = 0; kind < 2; ++kind)
      for (int n = 0; n < 100; ++n) {
        char* id = ids[kind][n];
        std::memcpy(id, kind ? "CBK-W" : "CBK-E", 5);
        id[5] = '0';
        id[6] = char('0' + n / 10);
        id[7] = char('0' + n % 10);
        id[8] = '\0';
      }
    return true;
  }();
  (void)filled;
  unsigned value = unsigned(check);
  if (value == 0) return "";
  if (value < 100) return ids[0][value];
  if (value > 1000 && value < 1100) return ids[1][value - 1000];
  return "CBK-?";
}

Status Status::error(ErrorCode code, Check check, const char* format, ...) noexcept {
  Status status;
  status.code_ = code;
  status.check_ = check;
  va_list args;
  va_start(args, format);
  std::vsnprintf(status.message_, sizeof status.message_, format, args);
  va_end(args);
  return status;
}

void Status::prefix(const char* text) noexcept {
  char joined[kMessageCapacity];
  const std::size_t text_length = std::strlen(text);
  std::size_t n = 0;
  // Manual join: truncating is intended, and snprintf would warn about it.
  for (std::size_t i = 0; i < text_length && n + 1 < sizeof joined; ++i)
    joined[n++] = text[i];
  for (const char* sep = ": "; *sep && n + 1 < sizeof joined; ++sep)
    joined[n++] = *sep;
  for (const char* m = message_; *m && n + 1 < sizeof joined; ++m)
    joined[n++] = *m;
  joined[n] = '\0';
  std::memcpy(message_, joined, sizeof joined);
}

}  // namespace clothbake::reader

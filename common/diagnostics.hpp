// Diagnostics on stderr (never stdout, which carries --json output) through spdlog.
// warn() also records the message so that a command can list its warnings in its JSON output.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace clothbake {

// Prints "clothbake: warning: MESSAGE" on stderr unless quiet, and records MESSAGE. Thread-safe.
void warn(const std::string& message);
// Prints "clothbake: MESSAGE" on stderr unless quiet. Thread-safe.
void info(const std::string& message);
// Prints "clothbake: error: MESSAGE" on stderr, always.
void report_error(const std::string& message);
// Every message that warn(), info() and report_error() print passes through `filter` first
// (recorded warnings stay as given); nullptr prints them as given. clothbake's main() sets
// terminal_safe (bake/inputs/terminal_text.hpp), so that control bytes in file names and keys never
// reach a terminal raw.
void set_message_filter(std::string (*filter)(std::string_view));
// Suppresses warn()/info() output (warnings are still recorded).
void set_quiet(bool quiet);
bool is_quiet();
// Returns and clears the recorded warnings, in the order they were issued.
std::vector<std::string> take_warnings();

}  // namespace clothbake

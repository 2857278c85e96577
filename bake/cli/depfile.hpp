// Make-syntax dependency files (`clothbake bake --depfile OUT.d`): one rule "TARGET: DEP..." that
// Ninja (`depfile =`, CMake's add_custom_command(DEPFILE)) and GNU Make (`-include *.d`) read.
#pragma once

#include <string>
#include <vector>

namespace clothbake::cli {

// One path escaped for a depfile as both Ninja (1.11) and GNU Make (4.3) parse it: space and tab
// -> "\ " / "\<tab>", '#' -> "\#", ':' -> "\:", '$' -> "$$", and a run of backslashes before a
// space, tab or '#' doubled (so that it stays literal). Throws Error(Input) naming the path for a
// newline or carriage return, which no depfile syntax can hold, and for a ':' that ends the path
// or follows a backslash, which the two read differently (Ninja keeps "\:" before a blank).
std::string escape_depfile_path(const std::string& path);

// "TARGET: \\\n  DEP \\\n  DEP\n", dependencies in the given order without duplicates, then an
// empty phony rule per dependency ("DEP:\n"), so that Make does not fail when one is deleted.
std::string depfile_text(const std::string& target, const std::vector<std::string>& deps);

// Path of the running executable (/proc/self/exe), or "" when it cannot be read.
std::string current_executable();

}  // namespace clothbake::cli

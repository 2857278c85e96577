// Make-syntax dependency files (`clothbake bake --depfile OUT.d`): one rule "TARGET: DEP..." that
// Ninja (`depfile =`, CMake's add_custom_command(DEPFILE)) and GNU Make (`-include *.d`) read.
#pragma once

#include <string>
#include <vector>

namespace clothbake::cli {

// One path escaped for a depfile as both Ninja and GNU Make parse it: space and tab -> "\ " /
// "\<tab>", '#' -> "\#", '$' -> "$$", and a run of backslashes before a space, tab or '#' doubled
// (so that it stays literal). Throws Error(Input) naming the path for a newline or carriage
// return, which no depfile syntax can hold.
std::string escape_depfile_path(const std::string& path);

// "TARGET: \\\n  DEP \\\n  DEP\n", dependencies in the given order without duplicates, then an
// empty phony rule per dependency ("DEP:\n"), so that Make does not fail when one is deleted.
std::string depfile_text(const std::string& target, const std::vector<std::string>& deps);

// Path of the running executable (/proc/self/exe), or "" when it cannot be read.
std::string current_executable();

// Writes depfile_text atomically to `path` (Error(Input) when it cannot be written).
void write_depfile(const std::string& path, const std::string& target,
                   const std::vector<std::string>& deps);

}  // namespace clothbake::cli

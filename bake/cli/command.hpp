// Subcommand registry of the clothbake CLI.
//
// Each subcommand lives in its own bake/cli/cmd_<name>.cpp and registers itself at static
// initialisation time (the CLI sources are compiled straight into the executable, so no object is
// dropped by the linker). setup() adds the subcommand's options and returns the action run when the
// subcommand is selected; the action returns the process exit code or throws clothbake::Error.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clothbake::cli {

using Action = std::function<int()>;

struct Command {
  std::string name;
  std::string description;
  std::function<Action(CLI::App& subcommand)> setup;
};

// Adds a command; returns true so that it can initialise a namespace-scope constant.
bool register_command(Command command);
// All registered commands, sorted by name.
std::vector<Command> registered_commands();

// Prints JSON on stdout (pretty, 2-space indent, trailing newline): the machine output of --json.
void print_json(const nlohmann::json& value);
// Flushes stdout and throws Error(Input) "cannot write to standard output: ..." when what was
// written did not reach it (a full disk, /dev/full, a closed pipe): for a command that must know
// before it commits an output.
void require_stdout_written();
// Flushes stdout; returns `code`, or 2 (ExitCode::Input) with an error on stderr when anything
// written to stdout was lost (disk full, /dev/full, closed pipe). main() applies it to every
// action.
int checked_stdout(int code);

// Option groups (--json, ASSET) and value parsers shared by the commands: options.hpp.

}  // namespace clothbake::cli

// clothbake: the command-line entry point. Subcommands register themselves (see command.hpp).
// Exit codes (docs/cli.md): 0 ok, 1 usage, 2 input or I/O error, 3 invalid asset, 4 internal error.
// SIGINT, SIGTERM and SIGHUP remove the temporary output files, then end the process by the
// signal (common/temp_registry.hpp).
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>

#include "bake/cli/command.hpp"
#include "bake/inputs/fabric_toml.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/temp_registry.hpp"
#include "common/version.hpp"

namespace clothbake::cli {
namespace {
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace

bool register_command(Command command) {
  registry().push_back(std::move(command));
  return true;
}

std::vector<Command> registered_commands() {
  auto commands = registry();
  std::sort(commands.begin(), commands.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  return commands;
}

}  // namespace clothbake::cli

int main(int argc, char** argv) {
  using namespace clothbake;
  // First: a Ctrl-C at any later point must not leave a temporary output file behind.
  install_temp_file_signal_handlers();
  // Diagnostics name files and keys as given: escape what a terminal would interpret (docs/cli.md).
  set_message_filter(&terminal_safe);
  CLI::App app{
      "clothbake: offline precompute and asset baking for the multi-scale cloth appearance model"};
  app.set_version_flag("--version", std::string("clothbake ") + CLOTHBAKE_VERSION_STRING);
  app.require_subcommand(1);
  app.fallthrough(false);
  std::map<CLI::App*, cli::Action> actions;
  for (const auto& command : cli::registered_commands()) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    actions[sub] = command.setup(*sub);
  }
  // A mistyped command: name it and the closest one (CLI11 would only say that one is required).
  if (argc >= 2 && argv[1][0] != '-') {
    std::vector<std::string> names;
    for (const auto& command : cli::registered_commands())
      names.push_back(command.name);
    if (std::find(names.begin(), names.end(), argv[1]) == names.end()) {
      const std::string near = inputs::closest_match(argv[1], names);
      report_error("unknown command '" + std::string(argv[1]) + "'" +
                   (near.empty() ? std::string() : "; did you mean '" + near + "'?") +
                   " (clothbake --help lists the commands)");
      return int(ExitCode::Usage);
    }
  }
  // Where a usage error's options are listed: the deepest subcommand named on the command line
  // ("clothbake report plan --help"), for CLI11's refusals and for the actions' own alike.
  std::string where = "clothbake";
  const CLI::App* level = &app;
  for (int i = 1; i < argc; ++i) {
    const CLI::App* next = nullptr;
    for (const CLI::App* sub : level->get_subcommands({}))
      if (sub->get_name() == argv[i]) next = sub;
    if (next == nullptr) continue;  // a positional or an option ("query ASSET radiance")
    where += " " + next->get_name();
    level = next;
  }
  where += " --help";
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version: printed on stdout
    // One error style for every message (docs/cli.md): "clothbake: error: ..." and where the
    // options are listed, instead of CLI11's bare text and "Run with --help".
    // A missing or mistyped subcommand of a command that has them: name the valid ones.
    std::string message = e.what();
    if (level != &app && !level->get_subcommands({}).empty() &&
        message.find("subcommand is required") != std::string::npos) {
      const std::vector<const CLI::App*> subs = level->get_subcommands({});
      message = level->get_name() + " needs one of ";
      for (std::size_t k = 0; k < subs.size(); ++k)
        message += (k == 0 ? "" : k + 1 == subs.size() ? " or " : ", ") + subs[k]->get_name();
    }
    report_error(message + " (" + where + " lists the options)");
    return int(ExitCode::Usage);
  }
  try {
    for (auto& [sub, action] : actions)
      if (sub->parsed()) return cli::checked_stdout(action());
    return int(ExitCode::Usage);
  } catch (const CLI::ParseError& e) {
    // Validation that needs more than CLI11 can express (thrown by an action before any output).
    report_error(std::string(e.what()) + " (" + where + " lists the options)");
    return int(ExitCode::Usage);
  } catch (const Error& e) {
    // A library's refusal of an option value (Error(Usage), naming the option) reads like the
    // parser's: it says where the options are listed.
    report_error(e.code() == ExitCode::Usage
                     ? std::string(e.what()) + " (" + where + " lists the options)"
                     : std::string(e.what()));
    return int(e.code());
  } catch (const std::bad_alloc&) {
    report_error("out of memory");
    return int(ExitCode::Internal);
  } catch (const std::exception& e) {
    report_error(std::string("internal error: ") + e.what());
    return int(ExitCode::Internal);
  }
}

// The commands' standard output (command.hpp): JSON documents and the check that what a command
// printed reached stdout. In clothbake_cli, so that command libraries (report stability) print
// through the same functions as the executable's commands.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>

#include "bake/cli/command.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"

namespace clothbake::cli {

void print_json(const nlohmann::json& value) {
  // Paths and names are bytes: a byte that is not UTF-8 is written as U+FFFD instead of failing
  // (docs/cli.md, "Machine output").
  std::cout << value.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  std::cout.flush();
}

void require_stdout_written() {
  // A command's output that did not reach stdout (a full disk, /dev/full, a closed pipe) is an
  // I/O error, not a success (docs/cli.md, exit code 2).
  std::cout.flush();
  errno = 0;
  const bool failed = std::cout.fail() || std::fflush(stdout) != 0 || std::ferror(stdout);
  if (!failed) return;
  const int err = errno;
  throw Error(ExitCode::Input, std::string("cannot write to standard output") +
                                   (err ? std::string(": ") + std::strerror(err) : std::string()));
}

int checked_stdout(int code) {
  try {
    require_stdout_written();
  } catch (const Error& e) {
    report_error(e.what());
    return code != 0 ? code : int(e.code());
  }
  return code;
}

}  // namespace clothbake::cli

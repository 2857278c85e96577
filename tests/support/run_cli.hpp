// Runs the built `clothbake` executable as a child process for end-to-end CLI tests: exit code,
// stdout and stderr captured separately. One implementation for every CLI test (they used to carry
// their own popen() copies).
//
// The executable is CLOTHBAKE_EXE when the test target defines it (preferred:
// target_compile_definitions(T PRIVATE CLOTHBAKE_EXE="$<TARGET_FILE:clothbake>")), else
// CLOTHBAKE_BINARY_DIR/bin/clothbake; $CLOTHBAKE_TEST_EXE overrides both. POSIX only (fork/exec);
// not thread-safe with respect to other fork()s in the same test process.
#pragma once

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace clothbake::test_support {

struct CliRun {
  int code = -1;  // exit status; -1 if the process did not exit normally (signal, exec failure)
  long max_rss_kb = 0;  // the child's peak resident set (getrusage's ru_maxrss), KiB
  std::string out, err;
};

inline std::string clothbake_executable() {
  // $CLOTHBAKE_TEST_EXE overrides, e.g. to check that a regression test fails on an older build.
  if (const char* exe = std::getenv("CLOTHBAKE_TEST_EXE"); exe && *exe) return exe;
#ifdef CLOTHBAKE_EXE
  return CLOTHBAKE_EXE;
#else
  return std::string(CLOTHBAKE_BINARY_DIR) + "/bin/clothbake";
#endif
}

namespace detail {
inline std::string slurp_and_remove(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  in.close();
  std::error_code ec;
  std::filesystem::remove(path, ec);
  return ss.str();
}

// argv[0] is the program to execute (execv, no PATH lookup, no shell).
inline CliRun spawn(const std::vector<std::string>& argv) {
  static std::atomic<int> counter{0};
  const std::string stem =
      "clothbake_cli_" + std::to_string(::getpid()) + "_" + std::to_string(counter.fetch_add(1));
  const auto dir = std::filesystem::temp_directory_path();
  const auto out_path = dir / (stem + ".out");
  const auto err_path = dir / (stem + ".err");
  std::vector<char*> args;
  for (const auto& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(nullptr);
  CliRun r;
  const pid_t pid = ::fork();
  if (pid < 0) return r;
  if (pid == 0) {
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (out < 0 || err < 0 || ::dup2(out, 1) < 0 || ::dup2(err, 2) < 0) ::_exit(127);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  struct rusage usage {};
  pid_t waited;
  do {
    waited = ::wait4(pid, &status, 0, &usage);
  } while (waited < 0 && errno == EINTR);
  r.max_rss_kb = usage.ru_maxrss;
  r.code = waited == pid && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp_and_remove(out_path);
  r.err = slurp_and_remove(err_path);
  return r;
}
}  // namespace detail

// `clothbake ARGS...`: each element is one argument, passed verbatim (no shell, no quoting).
inline CliRun run_clothbake(const std::vector<std::string>& args) {
  std::vector<std::string> argv{clothbake_executable()};
  argv.insert(argv.end(), args.begin(), args.end());
  return detail::spawn(argv);
}

// `clothbake ARGS...` with its stderr on a pseudo-terminal (what a user at a terminal sees:
// progress bars, status lines) and its stdout captured apart; `err` holds what reached the
// terminal, carriage returns and escape sequences included. For tests of terminal-only output.
inline CliRun run_clothbake_on_terminal(const std::vector<std::string>& args) {
  CliRun r;
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) return r;
  const char* slave_name = ::ptsname(master);
  if (slave_name == nullptr) return r;
  const std::string slave_path = slave_name;
  static std::atomic<int> counter{0};
  const auto out_path = std::filesystem::temp_directory_path() /
                        ("clothbake_tty_" + std::to_string(::getpid()) + "_" +
                         std::to_string(counter.fetch_add(1)) + ".out");
  std::vector<std::string> argv{clothbake_executable()};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargs;
  for (const auto& a : argv)
    cargs.push_back(const_cast<char*>(a.c_str()));
  cargs.push_back(nullptr);
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return r;
  if (pid == 0) {
    ::setsid();
    const int slave = ::open(slave_path.c_str(), O_RDWR);
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (slave < 0 || out < 0 || ::dup2(out, 1) < 0 || ::dup2(slave, 2) < 0) ::_exit(127);
    ::close(master);
    ::execv(cargs[0], cargs.data());
    ::_exit(127);
  }
  char buffer[4096];
  for (;;) {  // until the child closes the terminal (EIO once no slave is open)
    const ssize_t n = ::read(master, buffer, sizeof buffer);
    if (n > 0) {
      r.err.append(buffer, std::size_t(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;
  }
  int status = 0;
  pid_t waited;
  do {
    waited = ::waitpid(pid, &status, 0);
  } while (waited < 0 && errno == EINTR);
  ::close(master);
  r.code = waited == pid && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = detail::slurp_and_remove(out_path);
  return r;
}

// `clothbake COMMAND_LINE` through /bin/sh -c: the words are split and quoted by the shell, as if
// typed. For tests whose argument lists read best as one string.
inline CliRun run_clothbake_line(const std::string& command_line) {
  return detail::spawn({"/bin/sh", "-c", "exec '" + clothbake_executable() + "' " + command_line});
}

}  // namespace clothbake::test_support

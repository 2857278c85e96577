// Child processes (child_process.hpp).
#include "common/child_process.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

extern char** environ;

namespace clothbake {

ChildStart start_child(const std::function<int()>& body) {
  std::fflush(nullptr);
  ChildStart out;
  const pid_t pid = ::fork();
  if (pid < 0) {
    out.error = errno;
    return out;
  }
  if (pid == 0) {
    int code = kChildBodyThrewExitCode;
    try {
      code = body();
    } catch (...) {
      code = kChildBodyThrewExitCode;
    }
    std::fflush(nullptr);  // what the body printed through stdio (_exit does not flush)
    ::_exit(code);
  }
  out.pid = pid;
  return out;
}

ChildStart spawn_program(const std::string& exe, const std::vector<std::string>& args,
                         const std::string& stdout_path, const std::string& stderr_path) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 2);
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  ChildStart out;
  posix_spawn_file_actions_t actions;
  int rc = posix_spawn_file_actions_init(&actions);
  if (rc != 0) {
    out.error = rc;
    return out;
  }
  // "/dev/null" is opened as it is (never created, should it be missing); files are created.
  auto flags = [](const std::string& path) {
    return path == "/dev/null" ? O_WRONLY : O_WRONLY | O_CREAT | O_TRUNC;
  };
  if (!stdout_path.empty())
    rc = posix_spawn_file_actions_addopen(&actions, 1, stdout_path.c_str(), flags(stdout_path),
                                          0644);
  if (rc == 0 && !stderr_path.empty())
    rc = posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), flags(stderr_path),
                                          0644);
  pid_t pid = -1;
  if (rc == 0) rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    out.error = rc;
    return out;
  }
  out.pid = pid;
  return out;
}

ChildWait wait_child(pid_t pid, double timeout_seconds) {
  ChildWait out;
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    int status = 0;
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) {
      out.ended = true;
      out.status = status;
      return out;
    }
    if (r < 0 && errno != EINTR) {
      out.error = errno;
      return out;
    }
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (elapsed > timeout_seconds) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      out.timed_out = true;
      out.status = status;
      return out;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

ChildEnd wait_any_child() {
  ChildEnd out;
  for (;;) {
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid >= 0) {
      out.pid = pid;
      out.status = status;
      return out;
    }
    if (errno != EINTR) {
      out.error = errno;
      return out;
    }
  }
}

bool child_succeeded(int wait_status) {
  return WIFEXITED(wait_status) && WEXITSTATUS(wait_status) == 0;
}

int child_signal(int wait_status) {
  return WIFSIGNALED(wait_status) ? WTERMSIG(wait_status) : 0;
}

std::string describe_wait_status(int wait_status) {
  if (WIFEXITED(wait_status)) return "exit code " + std::to_string(WEXITSTATUS(wait_status));
  if (WIFSIGNALED(wait_status)) return "killed by signal " + std::to_string(WTERMSIG(wait_status));
  char hex[16];
  std::snprintf(hex, sizeof hex, "%#x", unsigned(wait_status));
  return std::string("wait status ") + hex;
}

}  // namespace clothbake

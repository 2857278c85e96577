// Child processes: the one place that forks, spawns and waits. Two users: `clothbake batch`
// (bake/cli/batch_run.cpp) spawns one `clothbake bake` per fabric with its stdout and stderr in
// files and waits for whichever ends first; `report stability` (bake/reports/stability_baked.cpp)
// runs each baked case in a forked child with a time limit, killed when it overruns.
//
// POSIX (fork, posix_spawn, waitpid, kill); C++20, standard library only. Wait statuses are the
// raw `int` of waitpid(2); child_succeeded, child_signal and describe_wait_status read them, so
// that callers need not include <sys/wait.h>. Nothing here installs signal handlers or changes
// the disposition of SIGCHLD.
#pragma once

#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace clothbake {

// A child that was started, or why it was not.
struct ChildStart {
  pid_t pid = -1;  // the child's process id; -1 when it was not started
  int error = 0;   // when pid is -1: the errno value of fork or posix_spawn (0 otherwise)
  bool ok() const { return pid > 0; }
};

// The exit code of a forked child whose body threw an exception (any type) out of `body`.
inline constexpr int kChildBodyThrewExitCode = 70;

// Flushes every stdio stream (so that buffered output is not written twice), then forks. The
// child runs `body`, flushes stdio and leaves with _exit(body's return value; only its low 8
// bits reach the parent, so return 0..255), without running atexit handlers or the parent's
// static destructors (iostreams are not flushed: close them in the body); an exception escaping
// `body` ends it with
// _exit(kChildBodyThrewExitCode). The parent gets the pid at once (it must reap the child: one of
// the wait functions below), or pid -1 and fork's errno (EAGAIN, ENOMEM) with no child.
// Allocates nothing itself (building the std::function may). Not thread-safe in the sense that
// matters for fork: call before this process starts any other thread (TBB's pool in particular),
// since the child holds only the calling thread and every lock another thread held stays locked in
// it.
ChildStart start_child(const std::function<int()>& body);

// Starts the program `exe` (a path; PATH is not searched) with argv = {exe, args...} and this
// process's environment, through posix_spawn. `stdout_path` and `stderr_path`, when not empty,
// are opened for the child as its fd 1 and fd 2: write-only, created with mode 0644 less the
// umask and truncated, except "/dev/null" (discards; opened as it is, never created); empty
// keeps this process's stream. Returns the pid, or pid -1 and the error number when the program
// cannot be started: a missing or non-executable `exe`, an output file that cannot be opened
// (glibc reports both from the child's exec or open), or EAGAIN/ENOMEM. The child inherits every
// descriptor not marked close-on-exec. Allocates the argv array. Thread-safe (posix_spawn does
// not duplicate other threads), unlike start_child.
ChildStart spawn_program(const std::string& exe, const std::vector<std::string>& args,
                         const std::string& stdout_path, const std::string& stderr_path);

// How waiting for one child ended.
struct ChildWait {
  bool ended = false;      // it ended by itself within the limit (`status` is its wait status)
  bool timed_out = false;  // it ran past the limit: sent SIGKILL and reaped (`status`)
  int status = 0;          // the wait status (ended or timed_out)
  int error = 0;           // neither: the errno value of waitpid (ECHILD: not a child of ours)
};

// Waits for the child `pid` for at most `timeout_seconds` seconds of wall time (steady clock,
// from this call), polling waitpid(pid, WNOHANG) every 20 ms. A child still running after that is
// sent SIGKILL and reaped (blocking until it is gone): timed_out. A waitpid error other than
// EINTR (retried) ends the wait at once with `error` set and the child, if any, left running.
// Allocates nothing. Thread-safe for distinct pids; sleeps the calling thread.
ChildWait wait_child(pid_t pid, double timeout_seconds);

// One child that ended, or why none could be waited for.
struct ChildEnd {
  pid_t pid = -1;  // the child that ended; -1 on error
  int status = 0;  // its wait status
  int error = 0;   // when pid is -1: the errno value of waitpid (ECHILD: no child left)
};

// Blocks until any child of this process ends (waitpid(-1, ..., 0)) and reaps it; EINTR is
// retried. Each ended child is returned exactly once. It reaps children this process started in
// any way, so the caller must have no other children that some other code waits for. Allocates
// nothing. Thread-safe, but two threads waiting at once each get different children.
ChildEnd wait_any_child();

// True when `wait_status` is a normal exit with code 0. Pure.
bool child_succeeded(int wait_status);

// The signal that killed the child of `wait_status`, or 0 when no signal did (a normal exit).
// Pure.
int child_signal(int wait_status);

// `wait_status` in words: "exit code 3", "killed by signal 9", or "wait status 0x..." for
// anything else (a stopped child, which waitpid reports only with WUNTRACED). Allocates the
// string; pure and thread-safe.
std::string describe_wait_status(int wait_status);

}  // namespace clothbake

#include "common/temp_registry.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace clothbake {
namespace {

// A slot's life: kFree -> kFilling (the owner copies the path) -> kLiveFile or kLiveDirectory ->
// kFree when the owner unregisters, or -> kRemoving when a handler takes it (then it is never
// reused: the process is ending). The handler reads `path` only after winning the change to
// kRemoving, and the owner only writes it in kFilling, so the two never touch the bytes at the
// same time.
enum : int { kFree = 0, kFilling = 1, kLiveFile = 2, kLiveDirectory = 3, kRemoving = 4 };

static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

struct Slot {
  std::atomic<int> state{kFree};
  char path[kTempPathMax];
};

Slot g_slots[kTempSlots];

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

extern "C" void remove_temp_files_and_reraise(int signo) {
  const int saved_errno = errno;
  unlink_registered_temp_paths();
  // Default disposition, then the same signal again: it is blocked while this handler runs and is
  // delivered when it returns, so the process ends as if the handler had never been installed.
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigemptyset(&action.sa_mask);
  sigaction(signo, &action, nullptr);
  raise(signo);
  errno = saved_errno;
}

}  // namespace

int register_temp_path(const char* path, bool directory) noexcept {
  const std::size_t length = std::strlen(path);
  if (length == 0 || length >= kTempPathMax) return -1;
  for (int i = 0; i < kTempSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling, std::memory_order_acquire))
      continue;
    std::memcpy(g_slots[i].path, path, length + 1);
    g_slots[i].state.store(directory ? kLiveDirectory : kLiveFile, std::memory_order_release);
    return i;
  }
  return -1;
}

void unregister_temp_path(int slot) noexcept {
  if (slot < 0 || slot >= kTempSlots) return;
  for (const int live : {kLiveFile, kLiveDirectory}) {
    int expected = live;
    if (g_slots[slot].state.compare_exchange_strong(expected, kFree, std::memory_order_acq_rel))
      return;
  }
}

int unlink_registered_temp_paths() noexcept {
  int removed = 0;
  // Files first, so that a registered directory is empty when its turn comes.
  for (const int live : {kLiveFile, kLiveDirectory}) {
    for (Slot& slot : g_slots) {
      int expected = live;
      if (!slot.state.compare_exchange_strong(expected, kRemoving, std::memory_order_acq_rel))
        continue;
      if ((live == kLiveFile ? ::unlink(slot.path) : ::rmdir(slot.path)) == 0) ++removed;
    }
  }
  return removed;
}

void install_temp_file_signal_handlers() noexcept {
  static std::atomic<bool> installed{false};
  if (installed.exchange(true)) return;
  for (const int signo : kSignals) {
    struct sigaction old {};
    if (sigaction(signo, nullptr, &old) != 0) continue;
    if (!(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = remove_temp_files_and_reraise;
    // The other termination signals wait while one handler removes the files, so that a second
    // signal cannot end the process half-way through the list.
    sigemptyset(&action.sa_mask);
    for (const int other : kSignals)
      sigaddset(&action.sa_mask, other);
    action.sa_flags = SA_RESTART;
    sigaction(signo, &action, nullptr);
  }
}

}  // namespace clothbake

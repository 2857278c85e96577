// Temporary output files that a signal must not leave behind. Writers register each temporary path
// while it exists; on SIGINT, SIGTERM or SIGHUP the handler (installed once by the program's entry
// point) unlinks every registered path, restores the default disposition and re-raises the
// signal, so the process still ends "killed by signal N" (exit status 128 + N in a shell) and the
// previous output, which was never touched, stays intact.
//
// In common/ (not formats/writer) because writers of every layer use it: the asset writer, the
// fit-sheen header writer (sheen/ may only include model/ and common/) and the image outputs.
//
// The registry is async-signal-safe: a fixed table of kTempSlots paths of at most kTempPathMax
// bytes, claimed and released with lock-free atomics; nothing is allocated or locked in the
// handler. A path that does not fit (table full, path too long) is simply not registered: the
// writer still removes it on every normal exit, and the next write to that output removes it as a
// stale file (formats/writer/atomic_file.hpp). SIGKILL cannot be caught; the same stale-file
// clean-up covers it.
#pragma once

#include <cstddef>

namespace clothbake {

inline constexpr int kTempSlots = 64;
inline constexpr std::size_t kTempPathMax = 4096;  // bytes, including the terminating NUL

// Registers `path` (a NUL-terminated file name, absolute or relative to the working directory,
// which the program must not change while the file is registered). A `directory` is removed with
// rmdir after every registered file, so a temporary directory is removed when its files are
// registered too. Returns a slot for unregister_temp_path, or -1 when the path is not registered
// (table full or path too long). Thread-safe; never throws, never allocates.
int register_temp_path(const char* path, bool directory = false) noexcept;

// Forgets a slot from register_temp_path (a no-op for -1). Call it once the file is renamed into
// place or removed. Thread-safe. If a signal handler is already removing the file, the slot is left
// to it (the process is about to end).
void unregister_temp_path(int slot) noexcept;

// Unlinks every registered file, then removes every registered (by then empty) directory;
// returns how many were removed. Async-signal-safe (only
// atomics and unlink(2)). The slots it empties are never reused (it is meant for a process that
// is ending), so a test may call it outside a handler only a few times.
int unlink_registered_temp_paths() noexcept;

// Installs the SIGINT, SIGTERM and SIGHUP handlers described above, once per process. A signal
// that is ignored when the program starts (e.g. SIGINT for a background job of a non-interactive
// shell, SIGHUP under nohup) stays ignored. Not async-signal-safe; call it from main().
void install_temp_file_signal_handlers() noexcept;

}  // namespace clothbake

// Atomic output files: bytes go to a temporary file in the destination directory, which is
// flushed (fsync) and renamed over the destination only when complete; the directory is then
// fsynced. An interrupted or failed write (error, disk full, a signal) therefore never leaves a
// partial file at the destination and never destroys what was there before.
//
// Temporary files are never left behind either, as far as a process can see to it: each is
// registered for the SIGINT/SIGTERM/SIGHUP handler (common/temp_registry.hpp) and holds an
// exclusive flock(2) for its whole life. SIGKILL (or a power cut) can still leave one
// (".NAME.tmp-XXXXXX" beside the destination); the next TempFile for the same destination removes
// such files of its own name whose lock is free, i.e. that no live process is writing.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "formats/writer/sink.hpp"

namespace clothbake::formats {

class TempFile;

struct OutputOptions {
  // Replace an existing file that is not a clothbake asset (assets are always replaceable).
  bool force = false;
  // Only an existing clothbake asset (or, with force, any regular file) may be replaced. Off for
  // outputs that are not assets (images, reports): any existing regular file is replaced.
  bool require_asset_to_replace = true;
  // Test hook: wraps the file sink (e.g. in a sink that fails after N bytes).
  std::function<std::unique_ptr<Sink>(Sink& file)> wrap_sink;
  // When set, write_file_atomically does not rename the complete temporary file but hands it over
  // here: the caller commits it (TempFile::commit) once its other work has succeeded, or drops it
  // (the destructor removes it), so that a command that fails after writing leaves nothing.
  std::shared_ptr<TempFile>* defer_commit = nullptr;
};

// Checks that `path` can be written before a long computation starts. Throws Error(Input) when:
// the path is empty or a directory; its directory does not exist; it exists and is not a regular
// file; it exists, is not an asset and options.force is false (require_asset_to_replace);
// the directory is not writable.
void check_output_path(const std::filesystem::path& path, const OutputOptions& options);

// Checks that the folder `dir` exists or can be made later by create_directories (not now: a
// command that fails leaves nothing behind): its nearest existing ancestor, `dir` itself included,
// must be a writable folder. Throws Error(Input) "WHAT: ANCESTOR is not a folder" or "... is not a
// writable folder". Safe on any path; allocates only the paths.
void check_creatable_folder(const std::filesystem::path& dir, const std::string& what);

// A temporary file beside `destination` (same directory, so rename is atomic), removed by the
// destructor unless commit() succeeded. Its name is temp_file_prefix(destination), six random
// characters [A-Za-z0-9] (mkstemps) and `suffix`. It holds an exclusive flock until it is renamed
// or removed, and is registered with common/temp_registry so that a termination signal removes it.
class TempFile {
 public:
  // `suffix` is appended to the temporary name (OpenImageIO picks the format by extension).
  // First removes stale temporaries of the same destination and suffix
  // (remove_stale_temp_files). Throws Error(Input) when no temporary file can be created.
  explicit TempFile(const std::filesystem::path& destination, const std::string& suffix = "");
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  const std::filesystem::path& path() const { return temp_; }
  int fd() const { return fd_; }
  // fsync, close, rename over the destination, fsync the directory. Throws Error(Input).
  void commit();

 private:
  std::filesystem::path destination_;
  std::filesystem::path temp_;
  int fd_ = -1;       // written through; closed (and its error checked) before the rename
  int lock_fd_ = -1;  // same open file, holds the flock until after the rename
  int slot_ = -1;     // common/temp_registry slot
  bool committed_ = false;
};

// ".NAME.tmp-": the start of every temporary file name for `destination`. NAME is the file name,
// or for names longer than 200 bytes their first 191 bytes, '~' and 8 hex digits of a hash of the
// whole name (so that temporaries stay within the 255-byte limit and two long names sharing their
// first 200 bytes still have different prefixes).
std::string temp_file_prefix(const std::filesystem::path& destination);

// Removes the temporaries a killed writer left for `destination` and `suffix`: the regular files
// in its directory named temp_file_prefix(destination) + 6 characters [A-Za-z0-9] + suffix, whose
// exclusive flock can be taken at once (a live writer holds its own). Files of any other name,
// symbolic links, and files another process holds are never touched; errors are ignored (a file
// that cannot be removed stays). Returns the number removed. Safe on any directory contents.
int remove_stale_temp_files(const std::filesystem::path& destination,
                            const std::string& suffix = "");

// Removes `path` if it is a regular file (not a symbolic link) whose exclusive flock can be taken
// at once, i.e. no live TempFile holds it. Returns whether it was removed; errors are ignored.
bool remove_if_unlocked(const std::filesystem::path& path);

// check_output_path, then `produce` writes into a temporary file that is committed on success (or
// handed over uncommitted, OutputOptions::defer_commit).
// Anything `produce` throws propagates after the temporary file is removed.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(Sink&)>& produce, const OutputOptions& options);

// `text` as a file that is not an asset (reports, depfiles, scripts: any existing regular file is
// replaced; options.require_asset_to_replace false), through write_file_atomically. Throws
// Error(Input) naming the path when it cannot be written.
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

// True if the file at `path` starts with the asset magic bytes.
bool looks_like_asset(const std::filesystem::path& path);

}  // namespace clothbake::formats

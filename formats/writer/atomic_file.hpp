// Atomic output files: bytes go to a temporary file in the destination directory, which is
// flushed (fsync) and renamed over the destination only when complete; the directory is then
// fsynced. An interrupted or failed write (error, disk full, SIGKILL) therefore never leaves a
// partial file at the destination and never destroys what was there before. A killed process
// can leave its temporary file (".NAME.tmp-XXXXXX" beside the destination) behind.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "formats/writer/sink.hpp"

namespace clothbake::formats {

struct OutputOptions {
  // Replace an existing file that is not a clothbake asset (assets are always replaceable).
  bool force = false;
  // Only an existing clothbake asset (or, with force, any regular file) may be replaced. Off for
  // outputs that are not assets (images, reports): any existing regular file is replaced.
  bool require_asset_to_replace = true;
  // Test hook: wraps the file sink (e.g. in a sink that fails after N bytes).
  std::function<std::unique_ptr<Sink>(Sink& file)> wrap_sink;
};

// Checks that `path` can be written before a long computation starts. Throws Error(Input) when:
// the path is empty or a directory; its directory does not exist; it exists and is not a regular
// file; it exists, is not an asset and options.force is false (require_asset_to_replace);
// the directory is not writable.
void check_output_path(const std::filesystem::path& path, const OutputOptions& options);

// A temporary file beside `destination` (same directory, so rename is atomic), removed by the
// destructor unless commit() succeeded.
class TempFile {
 public:
  // `suffix` is appended to the temporary name (OpenImageIO picks the format by extension).
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
  int fd_ = -1;
  bool committed_ = false;
};

// check_output_path, then `produce` writes into a temporary file that is committed on success.
// Anything `produce` throws propagates after the temporary file is removed.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(Sink&)>& produce, const OutputOptions& options);

// True if the file at `path` starts with the asset magic bytes.
bool looks_like_asset(const std::filesystem::path& path);

}  // namespace clothbake::formats

#include "formats/writer/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>

#include <cerrno>
#include <cstring>
#include <fstream>

#include "common/error.hpp"
#include "formats/reader/layout.hpp"

namespace clothbake::formats {
namespace fs = std::filesystem;
namespace {

fs::path directory_of(const fs::path& path) {
  fs::path parent = path.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

std::string errno_text(int err) {
  return std::strerror(err);
}

}  // namespace

bool looks_like_asset(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[sizeof reader::kMagic];
  if (!in.read(magic, sizeof magic)) return false;
  return std::memcmp(magic, reader::kMagic, sizeof magic) == 0;
}

void check_output_path(const fs::path& path, const OutputOptions& options) {
  if (path.empty()) throw_input_error("no output path given");
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (fs::is_directory(status))
    throw_input_error(path.string() + " is a directory: give the output a file name, e.g. " +
                      (path / "fabric.cbk").string());
  const fs::path dir = directory_of(path);
  const fs::file_status dir_status = fs::status(dir, ec);
  if (!fs::exists(dir_status))
    throw_input_error("cannot write " + path.string() + ": directory " + dir.string() +
                      " does not exist");
  if (!fs::is_directory(dir_status))
    throw_input_error("cannot write " + path.string() + ": " + dir.string() +
                      " is not a directory");
  if (fs::exists(status)) {
    if (!fs::is_regular_file(status))
      throw_input_error(path.string() +
                        " exists and is not a regular file; refusing to replace it");
    if (options.require_asset_to_replace && !options.force && !looks_like_asset(path))
      throw_input_error(path.string() +
                        " exists and is not a clothbake asset; refusing to overwrite it (pass "
                        "--force to replace it)");
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw_input_error("cannot write " + path.string() + ": directory " + dir.string() +
                      " is not writable (" + errno_text(errno) + ")");
}

TempFile::TempFile(const fs::path& destination, const std::string& suffix)
    : destination_(destination) {
  const fs::path dir = directory_of(destination);
  // Built with append: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
  std::string leaf(1, '.');
  // A file name may be 255 bytes: the temporary's adds 12 and the suffix, so a long name is cut
  // to its first 200 bytes here (the temporary only needs to be unique, which mkstemp ensures).
  const std::string file_name = destination.filename().string();
  leaf.append(file_name, 0, std::min<std::size_t>(file_name.size(), 200))
      .append(".tmp-XXXXXX")
      .append(suffix);
  const std::string name = (dir / leaf).string();
  std::vector<char> buffer(name.begin(), name.end());
  buffer.push_back('\0');
  fd_ = ::mkstemps(buffer.data(), int(suffix.size()));
  if (fd_ < 0)
    throw_input_error("cannot write " + destination.string() +
                      ": cannot create a temporary file in " + dir.string() + ": " +
                      errno_text(errno));
  ::fcntl(fd_, F_SETFD, FD_CLOEXEC);
  temp_ = buffer.data();
  // mkstemp creates 0600; give the asset the permissions a plain create would.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd_, 0666 & ~mask);
}

TempFile::~TempFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
}

void TempFile::commit() {
  const std::string what = "cannot write " + destination_.string();
  if (::fsync(fd_) != 0) throw_input_error(what + ": fsync failed: " + errno_text(errno));
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) throw_input_error(what + ": close failed: " + errno_text(errno));
  if (::rename(temp_.c_str(), destination_.c_str()) != 0)
    throw_input_error(what + ": cannot rename " + temp_.string() + ": " + errno_text(errno));
  committed_ = true;
  // Make the rename itself durable. A failure here leaves a complete file: not an error.
  const int dir_fd = ::open(directory_of(destination_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

void write_file_atomically(const fs::path& path, const std::function<void(Sink&)>& produce,
                           const OutputOptions& options) {
  check_output_path(path, options);
  TempFile temp(path);
  FdSink file(temp.fd(),
              path.string() + " (temporary file " + temp.path().filename().string() + ")");
  if (options.wrap_sink) {
    std::unique_ptr<Sink> wrapped = options.wrap_sink(file);
    produce(*wrapped);
  } else {
    produce(file);
  }
  temp.commit();
}

}  // namespace clothbake::formats

#include "formats/writer/atomic_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/temp_registry.hpp"
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

bool is_alnum_ascii(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

// The leaf names mkstemps makes from temp_file_prefix(destination) + "XXXXXX" + suffix.
bool is_temp_name_of(const std::string& leaf, const std::string& prefix,
                     const std::string& suffix) {
  if (leaf.size() != prefix.size() + 6 + suffix.size()) return false;
  if (leaf.compare(0, prefix.size(), prefix) != 0) return false;
  if (leaf.compare(prefix.size() + 6, suffix.size(), suffix) != 0) return false;
  return std::all_of(leaf.begin() + std::ptrdiff_t(prefix.size()),
                     leaf.begin() + std::ptrdiff_t(prefix.size() + 6), is_alnum_ascii);
}

bool same_file(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

// Removes dir_fd/leaf if it is a regular file whose exclusive flock is free.
bool remove_at_if_unlocked(int dir_fd, const std::string& leaf) {
  // O_NOFOLLOW: a symbolic link of that name is not followed (and not removed); O_NONBLOCK: a
  // FIFO of that name does not block the open.
  const int fd = ::openat(dir_fd, leaf.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  struct stat opened {};
  struct stat named {};
  // A free lock means no live writer: each holds its temporary's lock until it is renamed away.
  // The name must still lead to the file that was locked when it is removed.
  const bool removed = ::fstat(fd, &opened) == 0 && S_ISREG(opened.st_mode) &&
                       ::flock(fd, LOCK_EX | LOCK_NB) == 0 &&
                       ::fstatat(dir_fd, leaf.c_str(), &named, AT_SYMLINK_NOFOLLOW) == 0 &&
                       same_file(opened, named) && ::unlinkat(dir_fd, leaf.c_str(), 0) == 0;
  ::close(fd);  // releases the lock
  return removed;
}

}  // namespace

bool remove_if_unlocked(const fs::path& path) {
  const int dir_fd = ::open(directory_of(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd < 0) return false;
  const bool removed = remove_at_if_unlocked(dir_fd, path.filename().string());
  ::close(dir_fd);
  return removed;
}

std::string temp_file_prefix(const fs::path& destination) {
  const std::string name = destination.filename().string();
  // Built with append: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
  std::string prefix(1, '.');
  if (name.size() <= 200) {
    prefix.append(name);
  } else {
    uint32_t hash = 2166136261u;  // FNV-1a: stable across builds, unlike std::hash
    for (const unsigned char c : name)
      hash = (hash ^ c) * 16777619u;
    char hex[9];
    std::snprintf(hex, sizeof hex, "%08x", unsigned(hash));
    prefix.append(name, 0, 191).append(1, '~').append(hex);
  }
  return prefix.append(".tmp-");
}

int remove_stale_temp_files(const fs::path& destination, const std::string& suffix) {
  const fs::path dir = directory_of(destination);
  const std::string prefix = temp_file_prefix(destination);
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd < 0) return 0;
  DIR* listing = ::fdopendir(::fcntl(dir_fd, F_DUPFD_CLOEXEC, 0));
  if (!listing) {
    ::close(dir_fd);
    return 0;
  }
  std::vector<std::string> candidates;
  while (const dirent* entry = ::readdir(listing)) {
    const std::string leaf = entry->d_name;
    if (is_temp_name_of(leaf, prefix, suffix)) candidates.push_back(leaf);
  }
  ::closedir(listing);
  int removed = 0;
  for (const std::string& leaf : candidates)
    if (remove_at_if_unlocked(dir_fd, leaf)) {
      ++removed;
      info("removed " + (dir / leaf).string() + ", a temporary file left by an interrupted write");
    }
  ::close(dir_fd);
  return removed;
}

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

void check_creatable_folder(const fs::path& dir, const std::string& what) {
  std::error_code ec;
  fs::path existing = dir.empty() ? fs::path(".") : dir;
  while (!fs::exists(fs::symlink_status(existing, ec)) && existing.has_parent_path() &&
         existing.parent_path() != existing)
    existing = existing.parent_path();
  if (!fs::exists(fs::symlink_status(existing, ec))) existing = ".";  // a relative path's root
  if (!fs::is_directory(existing, ec))
    throw_input_error(what + ": " + existing.string() + " is not a folder");
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    throw_input_error(what + ": " + existing.string() + " is not a writable folder (" +
                      errno_text(errno) + ")");
}

TempFile::TempFile(const fs::path& destination, const std::string& suffix)
    : destination_(destination) {
  const fs::path dir = directory_of(destination);
  remove_stale_temp_files(destination, suffix);
  // A file name may be 255 bytes: the temporary's prefix keeps at most 200 of them, plus 12 and
  // the suffix (the temporary only needs to be unique, which mkstemps ensures).
  const std::string name = (dir / (temp_file_prefix(destination) + "XXXXXX" + suffix)).string();
  // Between mkstemps and flock another writer's clean-up may take the new file for a stale one: it
  // then holds the lock (flock fails here) or has already removed the name (the name no longer
  // leads to this file). Either way this one is given up and another name is tried.
  for (int attempt = 0; attempt < 16 && fd_ < 0; ++attempt) {
    std::vector<char> buffer(name.begin(), name.end());
    buffer.push_back('\0');
    const int fd = ::mkstemps(buffer.data(), int(suffix.size()));
    if (fd < 0)
      throw_input_error("cannot write " + destination.string() +
                        ": cannot create a temporary file in " + dir.string() + ": " +
                        errno_text(errno));
    ::fcntl(fd, F_SETFD, FD_CLOEXEC);
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      if (errno == EWOULDBLOCK) {  // a clean-up holds it, and removes it
        ::close(fd);
        continue;
      }
      // A file system without flock: written unlocked. Clean-ups cannot lock it either, so they
      // never take it for stale (nor any killed writer's there).
    } else {
      struct stat opened {};
      struct stat named {};
      if (::fstat(fd, &opened) != 0 || ::stat(buffer.data(), &named) != 0 ||
          !same_file(opened, named)) {
        ::close(fd);
        continue;
      }
    }
    fd_ = fd;
    temp_ = buffer.data();
  }
  if (fd_ < 0)
    throw_input_error("cannot write " + destination.string() +
                      ": cannot lock a temporary file in " + dir.string());
  // The lock belongs to the open file, not the descriptor: a duplicate keeps it until after the
  // rename while fd_ is closed before it (so that a failing close is still reported).
  lock_fd_ = ::fcntl(fd_, F_DUPFD_CLOEXEC, 0);
  // Absolute: the signal handler must find the file whatever the working directory is then.
  std::error_code ec;
  const fs::path absolute = fs::absolute(temp_, ec);
  slot_ = register_temp_path(ec ? temp_.c_str() : absolute.c_str());
  // mkstemp creates 0600; give the asset the permissions a plain create would.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd_, 0666 & ~mask);
}

TempFile::~TempFile() {
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
  unregister_temp_path(slot_);
  if (fd_ >= 0) ::close(fd_);
  if (lock_fd_ >= 0) ::close(lock_fd_);
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
  unregister_temp_path(slot_);
  slot_ = -1;
  ::close(lock_fd_);
  lock_fd_ = -1;
  // Make the rename itself durable. A failure here leaves a complete file: not an error.
  const int dir_fd = ::open(directory_of(destination_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

void write_text_atomically(const fs::path& path, const std::string& text) {
  OutputOptions options;
  options.require_asset_to_replace = false;
  write_file_atomically(
      path, [&](Sink& sink) { sink.write(text.data(), text.size()); }, options);
}

void write_file_atomically(const fs::path& path, const std::function<void(Sink&)>& produce,
                           const OutputOptions& options) {
  check_output_path(path, options);
  auto temp = std::make_shared<TempFile>(path);
  FdSink file(temp->fd(),
              path.string() + " (temporary file " + temp->path().filename().string() + ")");
  if (options.wrap_sink) {
    std::unique_ptr<Sink> wrapped = options.wrap_sink(file);
    produce(*wrapped);
  } else {
    produce(file);
  }
  if (options.defer_commit)
    *options.defer_commit = std::move(temp);
  else
    temp->commit();
}

}  // namespace clothbake::formats

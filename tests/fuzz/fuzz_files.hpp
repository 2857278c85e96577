// Files of the libFuzzer harnesses that read their input from disk (the loaders take paths).
#pragma once

#include <stdlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace clothbake::fuzz {

// The scratch directories of this process, removed when it exits normally (libFuzzer ends a run
// with exit(), which runs atexit handlers; a crash keeps them beside its reproducer).
inline std::vector<std::string>& scratch_directories() {
  static std::vector<std::string> dirs;
  return dirs;
}

// A fresh directory /tmp/clothbake-fuzz-NAME-XXXXXX (the harness's own, for its whole run).
inline std::string scratch_directory(const std::string& name) {
  std::string dir = "/tmp/clothbake-fuzz-" + name + "-XXXXXX";
  if (!::mkdtemp(dir.data())) __builtin_trap();
  if (scratch_directories().empty())
    std::atexit([] {
      for (const std::string& d : scratch_directories()) {
        std::error_code ignored;
        std::filesystem::remove_all(d, ignored);
      }
    });
  scratch_directories().push_back(dir);
  return dir;
}

// `size` bytes at `data` as the whole file at `path`.
inline void write_file(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) __builtin_trap();
  if (size && std::fwrite(data, 1, size, f) != size) __builtin_trap();
  std::fclose(f);
}

}  // namespace clothbake::fuzz

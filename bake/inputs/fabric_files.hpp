// File helpers of the fabric loader: whole-file reads, XXH64 content hashes, relative paths.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace clothbake::inputs {

// Largest text input read whole (fabric TOML, scene TOML): far above any real one.
inline constexpr std::size_t kMaxTextInputBytes = std::size_t(64) << 20;

// Throws Error(Input) "PREFIX: file not found" / "PREFIX: is a directory, expected a file" /
// "PREFIX: not a regular file (a FIFO, device or socket); clothbake reads only regular files"
// (prefix: `context: path`, or the path). Inputs are regular files only: a FIFO would block
// forever and /dev/zero or /dev/urandom never end.
void require_regular_file(const std::string& path, const std::string& context = {});

// The bytes of a regular file of at most `max_bytes`. Throws Error(Input) as require_regular_file,
// "PATH: cannot read (...)", or "PATH: larger than N MiB" (prefixed by `context` when it is not
// empty). Safe on any path.
std::string read_file_bytes(const std::string& path, const std::string& context = {},
                            std::size_t max_bytes = kMaxTextInputBytes);

// 16 lower-case hex digits of XXH64(bytes, seed 0).
std::string xxh64_hex(std::string_view bytes);

// XXH64 of a file's content (read_file_bytes + xxh64_hex).
std::string hash_file(const std::string& path, const std::string& context = {});

// `path` unchanged when absolute; otherwise joined to `base_dir` (the directory of the TOML file)
// and lexically normalised. An empty base_dir leaves relative paths relative to the working
// directory.
std::string resolve_relative(const std::string& base_dir, const std::string& path);

}  // namespace clothbake::inputs

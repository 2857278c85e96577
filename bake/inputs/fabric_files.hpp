// File helpers of the fabric loader: whole-file reads, XXH64 content hashes, relative paths.
#pragma once

#include <string>
#include <string_view>

namespace clothbake::inputs {

// The bytes of a file. Throws Error(Input) "PATH: file not found" / "PATH: cannot read (...)"
// prefixed by `context` when it is not empty. Safe on any path.
std::string read_file_bytes(const std::string& path, const std::string& context = {});

// 16 lower-case hex digits of XXH64(bytes, seed 0).
std::string xxh64_hex(std::string_view bytes);

// XXH64 of a file's content (read_file_bytes + xxh64_hex).
std::string hash_file(const std::string& path, const std::string& context = {});

// `path` unchanged when absolute; otherwise joined to `base_dir` (the directory of the TOML file)
// and lexically normalised. An empty base_dir leaves relative paths relative to the working
// directory.
std::string resolve_relative(const std::string& base_dir, const std::string& path);

}  // namespace clothbake::inputs

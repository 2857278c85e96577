#include "bake/inputs/fabric_files.hpp"

#include <fmt/format.h>
#include <xxhash.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/error.hpp"

namespace clothbake::inputs {

void require_regular_file(const std::string& path, const std::string& context) {
  const std::string prefix = context.empty() ? path : fmt::format("{}: {}", context, path);
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw_input_error(prefix + ": file not found");
  if (std::filesystem::is_directory(status))
    throw_input_error(prefix + ": is a directory, expected a file");
  if (!std::filesystem::is_regular_file(status))
    throw_input_error(prefix +
                      ": not a regular file (a FIFO, device or socket); clothbake reads only "
                      "regular files");
}

std::string read_file_bytes(const std::string& path, const std::string& context,
                            std::size_t max_bytes) {
  std::string prefix = context.empty() ? path : fmt::format("{}: {}", context, path);
  require_regular_file(path, context);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > max_bytes)
    throw_input_error(fmt::format("{}: {} bytes, larger than the limit of {} MiB", prefix, size,
                                  max_bytes >> 20));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_input_error(fmt::format("{}: cannot open ({})", prefix, std::strerror(errno)));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw_input_error(prefix + ": read error");
  return std::move(bytes).str();
}

std::string xxh64_hex(std::string_view bytes) {
  return fmt::format("{:016x}", XXH64(bytes.data(), bytes.size(), 0));
}

std::string hash_file(const std::string& path, const std::string& context) {
  // Any size: hashed inputs include assets (render), which are not text inputs.
  return xxh64_hex(read_file_bytes(path, context, std::numeric_limits<std::size_t>::max()));
}

std::string resolve_relative(const std::string& base_dir, const std::string& path) {
  std::filesystem::path p(path);
  if (p.is_absolute() || base_dir.empty()) return p.lexically_normal().string();
  return (std::filesystem::path(base_dir) / p).lexically_normal().string();
}

}  // namespace clothbake::inputs

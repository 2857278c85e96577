// Whole-file reads for tests (header-only).
#pragma once

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace clothbake::test_support {

// The bytes of the file at `path`; "" when it cannot be opened.
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace clothbake::test_support

#include "bake/cli/depfile.hpp"

#include <unistd.h>

#include <set>

#include "common/error.hpp"

namespace clothbake::cli {

std::string escape_depfile_path(const std::string& path) {
  std::string out;
  std::size_t backslashes = 0;  // run of backslashes just copied
  for (std::size_t i = 0; i < path.size(); ++i) {
    const char c = path[i];
    if (c == '\n' || c == '\r')
      throw_input_error("cannot name '" + path + "' in a depfile: the path holds a line break");
    if (c == ':' && (backslashes > 0 || i + 1 == path.size()))
      throw_input_error("cannot name '" + path +
                        "' in a depfile: GNU Make and Ninja read a ':' at the end of a path or "
                        "after a backslash differently");
    if (c == ' ' || c == '\t' || c == '#' || c == ':') {
      out.append(backslashes, '\\');  // double the run: it stays literal
      out.push_back('\\');
      out.push_back(c);
    } else if (c == '$') {
      out += "$$";
    } else {
      out.push_back(c);
    }
    backslashes = c == '\\' ? backslashes + 1 : 0;
  }
  return out;
}

std::string depfile_text(const std::string& target, const std::vector<std::string>& deps) {
  std::string text = escape_depfile_path(target) + ":";
  std::set<std::string> seen;
  std::vector<std::string> unique;
  for (const auto& d : deps)
    if (seen.insert(d).second) unique.push_back(escape_depfile_path(d));
  for (const auto& d : unique)
    text += " \\\n  " + d;
  text += "\n";
  for (const auto& d : unique)
    text += "\n" + d + ":\n";
  return text;
}

std::string current_executable() {
  std::string buffer(4096, '\0');
  const ssize_t n = ::readlink("/proc/self/exe", buffer.data(), buffer.size());
  if (n <= 0 || std::size_t(n) >= buffer.size()) return "";
  buffer.resize(std::size_t(n));
  return buffer;
}

}  // namespace clothbake::cli

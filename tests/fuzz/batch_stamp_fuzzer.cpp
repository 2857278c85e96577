// libFuzzer harness of `clothbake batch`'s stamps (bake/cli/batch_stamp.hpp): any bytes as a
// stamp must read as up to date or not (a damaged stamp: "unreadable stamp", the fabric is baked
// again), never as an exception, an internal error or a crash; a stamp that holds reports the
// output's real size. And a stamp written for paths of any bytes (the input's bytes as the fabric,
// executable and options; inputs whose first byte is odd) reads back with every name matching:
// non-UTF-8 names are kept exactly.
// The stamp's files live in a scratch directory: out.cbk (the output) and in.toml (an input).
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "bake/cli/batch_stamp.hpp"
#include "tests/fuzz/fuzz_files.hpp"

namespace {

namespace fs = std::filesystem;
using clothbake::cli::StampKey;

struct Scratch {
  std::string output, input;
};

const Scratch& scratch() {
  static const Scratch s = [] {
    const std::string dir = clothbake::fuzz::scratch_directory("stamp");
    Scratch out{dir + "/out.cbk", dir + "/in.toml"};
    for (const std::string& path : {out.output, out.input})
      clothbake::fuzz::write_file(path, reinterpret_cast<const uint8_t*>("bytes"), 5);
    return out;
  }();
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const Scratch& s = scratch();
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const StampKey key{"tool", "/usr/bin/clothbake", "bake defaults", "fabric.toml", s.output};
  try {
    const clothbake::cli::StampCheck check = clothbake::cli::check_stamp(text, key);
    if (check.up_to_date && check.output_size != 5) __builtin_trap();
    if (!check.up_to_date && check.why.empty()) __builtin_trap();
    // Round trip with the input's bytes as names (for inputs of an odd first byte: half the
    // executions, so that the checks of any bytes above run twice as often).
    if (size == 0 || (data[0] & 1) == 0) return 0;
    const std::string bytes(text.substr(0, 64));
    const StampKey odd{"tool", bytes, "bake --scene " + bytes, bytes, s.output};
    const nlohmann::json report = {{"total", {{"peak_rss_bytes", 1}, {"wall_seconds", 0.5}}},
                                   {"inputs",
                                    {{{"role", "fabric"}, {"path", "ignored"}, {"xxh64", "0"}},
                                     {{"role", "map"}, {"path", s.input}, {"xxh64", "0"}}}}};
    const std::string stamp = clothbake::cli::make_stamp(odd, "", report);
    const clothbake::cli::StampCheck back = clothbake::cli::check_stamp(stamp, odd);
    // The fabric itself is an input: it exists only when the bytes name an existing file.
    struct stat st {};
    if (::stat(bytes.c_str(), &st) != 0 && back.up_to_date) __builtin_trap();
    if (!back.up_to_date && back.why.find("is gone") == std::string::npos &&
        back.why.find("changed") == std::string::npos)
      __builtin_trap();  // anything else means a name did not read back
  } catch (...) {
    __builtin_trap();
  }
  return 0;
}

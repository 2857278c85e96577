// libFuzzer harness of the fabric loader (bake/inputs/fabric_load.hpp): any bytes as a fabric
// TOML file must load to a fabric whose maps are finite and within the height limits, or fail
// with clothbake::Error of the input kind (exit 2), never an internal error, another exception or
// a crash. The text is written to fabric.toml in a scratch directory of its own (relative map and
// WIF paths resolve there: the files a fuzzed fabric may name are the TOML itself, missing ones,
// or absolute paths such as /dev/zero, which must be refused). Every input is loaded at
// resolution 16 (LoadOptions::resolution) so that an execution stays fast whatever [bake]
// resolution says; the key itself is still parsed and range-checked.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/map_limits.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "tests/fuzz/fuzz_files.hpp"

namespace {

const std::string& scratch_file() {
  static const std::string path = clothbake::fuzz::scratch_directory("toml") + "/fabric.toml";
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  clothbake::set_quiet(true);
  const std::string& path = scratch_file();
  clothbake::fuzz::write_file(path, data, size);
  try {
    clothbake::LoadOptions options;
    options.resolution = 16;
    const clothbake::LoadedFabric loaded = clothbake::load_fabric_description(path, options);
    const clothbake::FabricMaps& maps = loaded.fabric.maps;
    if (maps.resolution != 16 || maps.height.size() != maps.texel_count()) __builtin_trap();
    for (float h : maps.height)
      if (!(std::abs(h) <= clothbake::inputs::kMaxHeightTiles)) __builtin_trap();
  } catch (const clothbake::Error& e) {
    if (e.code() != clothbake::ExitCode::Input) __builtin_trap();
  } catch (...) {
    __builtin_trap();  // anything else would reach the CLI as an internal error (exit 4)
  }
  (void)clothbake::take_warnings();
  return 0;
}

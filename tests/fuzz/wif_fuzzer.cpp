// libFuzzer harness of the WIF reader (bake/inputs/wif.hpp): any bytes as a WIF file must parse
// to a draft whose sizes are within the documented bounds, or fail with clothbake::Error of the
// input kind (exit 2), never an internal error, another exception or a crash. Built with
// -fsanitize=fuzzer,address,undefined against the instrumented reader sources and the project's
// libraries (tests/fuzz/CMakeLists.txt).
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "bake/inputs/wif.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  clothbake::set_quiet(true);
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const clothbake::WifDraft draft = clothbake::parse_wif(text, "fuzz.wif");
    if (draft.shafts < 0 || draft.shafts > clothbake::kMaxWifShafts) __builtin_trap();
    if (draft.treadles < 0 || draft.treadles > clothbake::kMaxWifShafts) __builtin_trap();
    if (draft.threading.size() > std::size_t(clothbake::weave::kMaxRepeat)) __builtin_trap();
    if (draft.lifts.size() > std::size_t(clothbake::weave::kMaxRepeat)) __builtin_trap();
  } catch (const clothbake::Error& e) {
    if (e.code() != clothbake::ExitCode::Input) __builtin_trap();
  } catch (...) {
    __builtin_trap();  // anything else would reach the CLI as an internal error (exit 4)
  }
  (void)clothbake::take_warnings();
  return 0;
}

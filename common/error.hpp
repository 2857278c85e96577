// Error type and process exit codes shared by every clothbake component and the CLI.
//
// Contract: code that detects bad user input throws clothbake::Error with ExitCode::Input and a
// message that names the file and the key, section, line or pixel. The CLI maps the code to the
// process exit status (docs/cli.md lists them). Library code never calls exit().
#pragma once

#include <stdexcept>
#include <string>

namespace clothbake {

enum class ExitCode : int {
  Ok = 0,            // success
  Usage = 1,         // bad command line (unknown option, missing argument)
  Input = 2,         // bad input file or I/O error (missing file, invalid value, cannot write)
  InvalidAsset = 3,  // an asset failed validation (corrupt, truncated, wrong version)
  Internal = 4,      // a bug: an invariant of clothbake itself was violated
  VerificationFailed = 5,  // `clothbake verify` measured an error above a threshold
};

class Error : public std::runtime_error {
 public:
  Error(ExitCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ExitCode code() const noexcept { return code_; }

 private:
  ExitCode code_;
};

// Shorthands: throw input_error("fabric.toml: [yarn.warp] roughness = -1 is out of range ...").
[[noreturn]] inline void throw_input_error(const std::string& message) {
  throw Error(ExitCode::Input, message);
}
[[noreturn]] inline void throw_internal_error(const std::string& message) {
  throw Error(ExitCode::Internal, message);
}

}  // namespace clothbake

// What a report gives its command: the JSON document (`--json` prints it), the human summary
// (printed otherwise), and, when a check failed after everything was written, the failure the
// command turns into exit 5 (ExitCode::VerificationFailed) after printing. The reports write
// their files themselves; they print nothing on stdout (warnings and progress go to stderr).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace clothbake::reports {

struct ReportOutput {
  nlohmann::json doc;
  std::string summary;                 // lines ending in '\n'
  std::optional<std::string> failure;  // set: exit 5 with this message, after printing
};

}  // namespace clothbake::reports

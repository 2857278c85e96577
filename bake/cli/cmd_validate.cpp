// clothbake validate ASSET [--json]: every integrity check of docs/format.md ("Validation
// checks"): structure, header and section checksums, padding, section layouts, value ranges,
// metadata. Each finding has a stable ID (CBK-E012, CBK-W001...). Exit 0 when there is no error
// (warnings allowed), 3 when the asset is invalid, 2 when the file cannot be read.
#include <iostream>
#include <memory>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "common/diagnostics.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/metadata_json.hpp"
#include "formats/writer/open_asset.hpp"

namespace clothbake::cli {
namespace {

using namespace clothbake::reader;

struct Finding {
  std::string id;
  bool warning = false;
  int64_t section = -1;
  std::string message;
};

void collect(void* user, Check check, uint32_t section, const char* message) {
  static_cast<std::vector<Finding>*>(user)->push_back(
      {check_id(check), is_warning(check), section == kNoSection ? -1 : int64_t(section), message});
}

// Checks that need a JSON parser (the reader library has none): limits, syntax, "format" and the
// types of the known keys (formats::check_metadata, shared with every other command).
void check_metadata_json(const Asset& asset, std::vector<Finding>& findings) {
  std::string_view text;
  if (!asset.metadata_json(&text).ok()) return;  // reported as CBK-E019 already
  nlohmann::json metadata;
  for (const auto& f : formats::check_metadata(asset, &metadata))
    findings.push_back({check_id(f.check), false, -1, f.message});
}

Action setup_validate(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  add_asset_argument(app, *path);
  add_json_flag(app, *json);
  return [path, json] {
    std::vector<Finding> findings;
    Asset asset;
    const Status status = asset.open_file(path->c_str());
    if (status.code() == ErrorCode::Io || status.code() == ErrorCode::InvalidArgument)
      throw Error(formats::exit_code_of(status), formats::describe(status));
    if (!status.ok()) {
      report_open_failure(status, collect, &findings);
    } else {
      validate_asset(asset, collect, &findings);
      const bool structural_errors = std::any_of(findings.begin(), findings.end(),
                                                 [](const Finding& f) { return !f.warning; });
      if (!structural_errors) check_metadata_json(asset, findings);
    }
    std::size_t errors = 0, warnings = 0;
    for (const auto& f : findings)
      (f.warning ? warnings : errors)++;
    if (*json) {
      nlohmann::json list = nlohmann::json::array();
      for (const auto& f : findings) {
        nlohmann::json item = {
            {"id", f.id}, {"severity", f.warning ? "warning" : "error"}, {"message", f.message}};
        if (f.section >= 0) item["section"] = f.section;
        list.push_back(item);
      }
      print_json({{"path", *path},
                  {"valid", errors == 0},
                  {"errors", errors},
                  {"warnings", warnings},
                  {"findings", list}});
    } else {
      for (const auto& f : findings)
        std::cout << f.id << (f.warning ? " warning: " : " error: ") << terminal_safe(f.message)
                  << '\n';
      std::cout << terminal_safe(*path) << ": " << (errors ? "INVALID" : "valid") << " (" << errors
                << " errors, " << warnings << " warnings)\n";
      std::cout.flush();
    }
    return errors ? int(ExitCode::InvalidAsset) : 0;
  };
}

const bool validate_registered = register_command(
    {"validate", "Check an asset's integrity; findings carry stable IDs (CBK-Ennn)",
     setup_validate});

}  // namespace
}  // namespace clothbake::cli

// clothbake inspect FABRIC.toml [--json]: load and validate a fabric description and everything it
// refers to, then print the resolved maps (sizes, value ranges, statistics) and every resolved
// parameter, defaults included (docs/fabric-format.md). Exit 2 on any bad input; writes nothing.
#include <iostream>
#include <memory>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/fabric_report.hpp"
#include "bake/inputs/map_stats.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "common/diagnostics.hpp"

namespace clothbake::cli {
namespace {

struct InspectOptions {
  std::string fabric;
  bool json = false;
};

Action setup_inspect(CLI::App& app) {
  auto options = std::make_shared<InspectOptions>();
  app.add_option("FABRIC", options->fabric, "fabric description (TOML)")->required();
  add_json_flag(app, options->json);
  return [options] {
    take_warnings();  // only this fabric's warnings belong in the report
    LoadedFabric loaded = load_fabric_description(options->fabric);
    inputs::MapStats stats = inputs::map_stats(loaded.fabric.maps);
    std::vector<std::string> warnings = take_warnings();
    if (options->json) {
      nlohmann::json doc = inspect_json(loaded, stats, warnings);
      doc["fabric"] = options->fabric;
      print_json(doc);
    } else {
      std::cout << terminal_safe_lines(inspect_text(loaded, stats, warnings));
      std::cout.flush();
    }
    return 0;
  };
}

const bool inspect_registered = register_command(
    {"inspect", "Load and validate a fabric description; print its maps and resolved parameters",
     setup_inspect});

}  // namespace
}  // namespace clothbake::cli

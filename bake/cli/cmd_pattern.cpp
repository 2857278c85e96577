// clothbake pattern (--weave NAME | --wif FILE | FABRIC.toml) [--resolution N] -o DIR [--json]:
// write a fabric's feature maps as float EXR, 8-bit PNG previews and an editable fabric.toml that
// loads back to the same maps (docs/fabric-format.md, docs/weaves.md). Nothing is written when
// anything fails: the files are built in a temporary directory next to DIR and moved into place.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/fabric_report.hpp"
#include "bake/inputs/fabric_write.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/inputs/weave.hpp"
#include "common/diagnostics.hpp"

namespace clothbake::cli {
namespace {

// Resolution of generated weaves when neither the command line nor a fabric file gives one (the
// paper's feature maps are 256 x 256).
constexpr int kDefaultPatternResolution = kDefaultWeaveResolution;

struct PatternOptions {
  std::string weave_name, wif, fabric, output;
  std::optional<int> resolution;
  bool json = false;
};

Action setup_pattern(CLI::App& app) {
  auto o = std::make_shared<PatternOptions>();
  app.add_option("FABRIC", o->fabric, "fabric description (TOML) to take the maps from");
  app.add_option("--weave", o->weave_name,
                 "named weave, e.g. plain, twill2/1, twill3/1-left, satin5, satin8-3, basket2");
  app.add_option("--wif", o->wif, "WIF weaving draft");
  app.add_option("--resolution", o->resolution,
                 fmt::format("texels per tile side (default: the fabric's bake.resolution, or {} "
                             "for --weave/--wif)",
                             kDefaultPatternResolution))
      ->check(CLI::Range(kMinResolution, kMaxResolution));
  app.add_option("-o,--output", o->output, "output directory (created; other files in it are kept)")
      ->required();
  add_json_flag(app, o->json,
                "print the weave matrix, yarn colours and written files as JSON on stdout");
  return [o] {
    int sources = int(!o->weave_name.empty()) + int(!o->wif.empty()) + int(!o->fabric.empty());
    if (sources != 1)
      throw CLI::ValidationError("pattern",
                                 "give exactly one of --weave NAME, --wif FILE or FABRIC.toml");
    take_warnings();
    LoadedFabric loaded;
    std::string comment;
    if (!o->weave_name.empty()) {
      loaded =
          fabric_from_named_weave(o->weave_name, o->resolution.value_or(kDefaultPatternResolution));
      comment = fmt::format("Generated from the named weave \"{}\".", o->weave_name);
    } else if (!o->wif.empty()) {
      loaded = fabric_from_wif(o->wif, o->resolution.value_or(kDefaultPatternResolution));
      comment = fmt::format("Generated from the WIF draft {}.",
                            std::filesystem::path(o->wif).filename().string());
    } else {
      LoadOptions load_options;
      load_options.resolution = o->resolution;
      loaded = load_fabric_description(o->fabric, load_options);
      comment = fmt::format("Generated from the fabric description {}.",
                            std::filesystem::path(o->fabric).filename().string());
    }
    std::vector<WrittenFile> files = write_fabric_directory(loaded.fabric, o->output, comment);
    std::vector<std::string> warnings = take_warnings();
    if (o->json) {
      nlohmann::json yarns = nlohmann::json::array();
      for (std::size_t i = 0; i < loaded.fabric.yarns.size(); ++i) {
        const auto& y = loaded.fabric.yarns[i];
        yarns.push_back(
            {{"id", i}, {"name", y.name}, {"color", {y.color[0], y.color[1], y.color[2]}}});
      }
      nlohmann::json written = nlohmann::json::array();
      for (const auto& f : files)
        written.push_back({{"role", f.role}, {"path", f.path}});
      nlohmann::json inputs = nlohmann::json::array();
      for (const auto& in : loaded.fabric.inputs)
        inputs.push_back({{"role", in.role}, {"path", in.path}, {"xxh64", in.xxh64}});
      print_json({{"output", o->output},
                  {"name", loaded.fabric.name},
                  {"source", fabric_source_name(loaded.source)},
                  {"resolution", loaded.fabric.maps.resolution},
                  {"tile_size_mm", loaded.fabric.tile_size_mm > 0
                                       ? nlohmann::json(loaded.fabric.tile_size_mm)
                                       : nlohmann::json(nullptr)},
                  {"weave", weave_json(loaded)},
                  {"yarns", yarns},
                  {"files", written},
                  {"inputs", inputs},
                  {"warnings", warnings}});
    } else {
      std::cout << fmt::format("wrote {} files ({}x{} maps of '{}') to {}\n", files.size(),
                               loaded.fabric.maps.resolution, loaded.fabric.maps.resolution,
                               terminal_safe(loaded.fabric.name), terminal_safe(o->output));
      for (const auto& f : files)
        std::cout << "  " << terminal_safe(f.path) << "\n";
      std::cout.flush();
    }
    return 0;
  };
}

const bool pattern_registered = register_command(
    {"pattern",
     "Write a weave's or a fabric's feature maps (EXR + PNG previews) and an editable fabric.toml",
     setup_pattern});

}  // namespace
}  // namespace clothbake::cli

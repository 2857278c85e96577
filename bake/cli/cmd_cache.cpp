// clothbake cache info [DIR] [--json] | prune [DIR] [--max-size S | --all]: what the content-keyed
// cache of stage outputs holds, and least-recently-used pruning (docs/batch.md, "Cache"). DIR
// defaults to $CLOTHBAKE_CACHE. Exit 1 without a folder or for a bad size, 2 for an unreadable one.
#include <iostream>
#include <memory>

#include "bake/cache/stage_cache.hpp"
#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "common/error.hpp"

namespace clothbake::cli {
namespace {

struct CacheCommandOptions {
  std::string dir;
  bool json = false;
  std::string max_size;
  bool all = false;
};

std::string cache_folder(const CacheCommandOptions& o) {
  const std::string dir = cache::cache_dir_from(o.dir);
  if (dir.empty()) throw Error(ExitCode::Usage, "no cache folder: give DIR or set CLOTHBAKE_CACHE");
  return dir;
}

Action setup_cache(CLI::App& app) {
  auto o = std::make_shared<CacheCommandOptions>();
  app.require_subcommand(1);
  auto* info = app.add_subcommand("info", "entries and bytes per stage");
  info->add_option("DIR", o->dir, "cache folder (default: $CLOTHBAKE_CACHE)");
  add_json_flag(*info, o->json, "print JSON on stdout");
  auto* prune = app.add_subcommand("prune", "remove least recently used entries");
  prune->add_option("DIR", o->dir, "cache folder (default: $CLOTHBAKE_CACHE)");
  prune->add_option("--max-size", o->max_size, "keep at most this much (default 10G)");
  prune->add_flag("--all", o->all, "remove every entry");
  add_json_flag(*prune, o->json, "print JSON on stdout");
  return [o, info, prune] {
    const std::string dir = cache_folder(*o);
    if (info->parsed()) {
      const cache::CacheInfo i = cache::cache_info(dir);
      nlohmann::json stages = nlohmann::json::object();
      for (const auto& [stage, v] : i.per_stage)
        stages[stage] = {{"entries", v.first}, {"bytes", v.second}};
      if (o->json) {
        print_json({{"dir", dir},
                    {"entries", i.entries},
                    {"bytes", i.bytes},
                    {"temporary_files", i.temporary_files},
                    {"stages", stages}});
      } else {
        std::cout << terminal_safe(dir) << ": " << i.entries << " entries, " << i.bytes << " bytes";
        if (i.temporary_files) std::cout << ", " << i.temporary_files << " temporary files";
        std::cout << '\n';
        for (const auto& [stage, v] : i.per_stage)
          std::cout << "  " << terminal_safe(stage) << ": " << v.first << " entries, " << v.second
                    << " bytes\n";
      }
      return 0;
    }
    (void)prune;
    if (o->all && !o->max_size.empty())
      throw Error(ExitCode::Usage, "--all and --max-size exclude each other");
    const uint64_t max = o->all                ? 0
                         : o->max_size.empty() ? cache::kDefaultCacheMaxBytes
                                               : cache::parse_size(o->max_size, "--max-size");
    const cache::PruneResult r = cache::prune_cache(dir, max);
    if (o->json)
      print_json({{"dir", dir},
                  {"removed_entries", r.removed_entries},
                  {"removed_bytes", r.removed_bytes},
                  {"kept_entries", r.kept_entries},
                  {"kept_bytes", r.kept_bytes}});
    else
      std::cout << "removed " << r.removed_entries << " entries (" << r.removed_bytes
                << " bytes), kept " << r.kept_entries << " (" << r.kept_bytes << " bytes)\n";
    return 0;
  };
}

const bool cache_registered = register_command(
    {"cache", "The content-keyed cache of stage outputs: info, prune", setup_cache});

}  // namespace
}  // namespace clothbake::cli

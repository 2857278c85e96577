// clothbake batch (DIR | LIST.txt) -o OUTDIR [--jobs N] [--max-memory S] [--cache DIR]
// [--cache-max-size S] [--force-rebake] [--scene S] [--json] [--emit slurm]: bakes a library of
// fabrics (with --scene each one's plan for that scene, `bake --scene`), one
// `clothbake bake` child process per fabric (docs/batch.md). Up-to-date fabrics are skipped (a
// stamp per fabric: tool version, options, every input file's size, mtime and content hash, the
// output's size and mtime); a failure is reported and the rest go on; at most N bakes run at once
// and never more than fit in --max-memory by their measured peaks. Exit 0 when every fabric is
// baked or up to date, 2 when any failed (after all ran), 1 for a bad command line.
#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "bake/cache/stage_cache.hpp"
#include "bake/cli/batch_run.hpp"
#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/progress.hpp"
#include "bake/stages/memory_estimate.hpp"
#include "common/error.hpp"

namespace clothbake::cli {
namespace {

// The command line beyond the engine's options.
struct BatchCommandOptions {
  BatchOptions batch;
  std::string max_memory;
  std::string emit;
  bool json = false;
};

// --emit slurm: the failures on stderr, what was written on stdout.
int emit_slurm(const BatchCommandOptions& o, const std::vector<BatchJob>& jobs,
               uint64_t peak_estimate) {
  const SlurmScript s = write_slurm_script(o.batch, jobs, peak_estimate);
  int failed = 0;
  for (const auto& j : jobs)
    if (j.status == "failed") {
      std::cerr << "clothbake: " << terminal_safe(j.fabric) << ": " << terminal_safe(j.note)
                << "\n";
      ++failed;
    }
  if (o.json) {
    print_json({{"script", s.script},
                {"list", s.list},
                {"tasks", s.tasks},
                {"mem_mb", s.mem_mb},
                {"cpus_per_task", s.cpus_per_task},
                {"failed", failed}});
  } else {
    std::cout << "wrote " << terminal_safe(s.script) << " (" << s.tasks
              << " tasks); submit with: sbatch " << terminal_safe(s.script) << "\n";
  }
  return failed ? int(ExitCode::Input) : 0;
}

Action setup_batch(CLI::App& app) {
  auto o = std::make_shared<BatchCommandOptions>();
  app.add_option("SOURCE", o->batch.source,
                 "folder of fabric .toml files, or a list file (one per line)")
      ->required();
  app.add_option("-o,--output", o->batch.output_dir, "output folder: OUTDIR/<fabric stem>.cbk")
      ->required();
  app.add_option("--jobs", o->batch.jobs, "bakes at once (default 1; 0: one per core)")
      ->check(CLI::Range(0, 1024));
  app.add_option("--max-memory", o->max_memory,
                 "never start bakes whose measured peaks sum above this (default 80 % of RAM or of "
                 "the cgroup limit)");
  app.add_option("--cache", o->batch.cache,
                 "stage cache shared by the bakes (default $CLOTHBAKE_CACHE)");
  app.add_option("--cache-max-size", o->batch.cache_max_size, "bound of the cache (default 10G)");
  app.add_flag("--force-rebake", o->batch.force, "bake every fabric, up to date or not");
  app.add_option("--scene", o->batch.scene,
                 "bake each fabric's plan for this scene (`bake --scene`; a fabric the scene "
                 "does not use fails)");
  app.add_option("--emit", o->emit, "write a farm script instead of baking: slurm")
      ->check(CLI::IsMember({"slurm"}));
  add_json_flag(app, o->json, "print the summary as JSON on stdout");
  return [o] {
    const uint64_t max_memory = max_memory_option(o->max_memory, 0.8);
    if (!o->batch.cache_max_size.empty())
      (void)cache::parse_size(o->batch.cache_max_size, "--cache-max-size");
    if (!o->batch.scene.empty()) inputs::require_regular_file(o->batch.scene, "--scene");
    // The list first: a source that names no fabric leaves no OUTDIR behind.
    std::vector<BatchJob> jobs = list_batch_jobs(o->batch);
    const uint64_t unknown_peak = check_batch_stamps(o->batch, jobs);
    if (o->emit == "slurm") return emit_slurm(*o, jobs, unknown_peak);
    // On a terminal (not with --json): a line on stderr as each bake ends, so that a long batch is
    // not silent until its table; on a pipe only the table (stdout) and errors.
    const bool live = !o->json && pipeline::ProgressBar::stderr_is_terminal();
    const BatchRun run = run_batch(
        o->batch, jobs, max_memory, unknown_peak,
        [&](std::size_t to_bake, int at_once) {
          if (live && to_bake > 0)
            std::fprintf(stderr, "batch: baking %zu of %zu fabrics, %d at once\n", to_bake,
                         jobs.size(), at_once);
        },
        [&](const BatchJob& j, std::size_t ended, std::size_t to_bake) {
          if (live)
            std::fprintf(stderr, "[%zu/%zu] %s: %s in %.1f s%s%s\n", ended, to_bake,
                         terminal_safe(j.name).c_str(), j.status.c_str(), j.seconds,
                         j.note.empty() ? "" : ": ", terminal_safe(j.note).c_str());
        });
    const double wall = run.wall_seconds;
    int failed = 0, baked = 0, fresh = 0;
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& j : jobs) {
      failed += j.status == "failed";
      baked += j.status == "baked";
      fresh += j.status == "up-to-date";
      rows.push_back({{"fabric", j.fabric},
                      {"output", j.output},
                      {"status", j.status},
                      {"seconds", j.seconds},
                      {"size_bytes", j.size},
                      {"peak_rss_bytes", j.peak},
                      {"note", j.note}});
    }
    if (o->json) {
      print_json({{"fabrics", rows},
                  {"baked", baked},
                  {"up_to_date", fresh},
                  {"failed", failed},
                  {"jobs", run.at_once},
                  {"threads_per_bake", run.threads_per_bake},
                  {"max_memory_bytes", max_memory},
                  {"wall_seconds", wall}});
    } else {
      // Names and notes hold paths: escaped for the terminal (docs/cli.md).
      std::size_t width = 6;
      for (const auto& j : jobs)
        width = std::max(width, terminal_safe(j.name).size());
      std::cout << std::left << std::setw(int(width) + 2) << "fabric" << std::setw(12) << "status"
                << std::setw(10) << "seconds" << std::setw(12) << "size"
                << "note\n";
      for (const auto& j : jobs) {
        std::ostringstream secs;
        secs << std::fixed << std::setprecision(2) << j.seconds;
        std::cout << std::left << std::setw(int(width) + 2) << terminal_safe(j.name)
                  << std::setw(12) << j.status << std::setw(10) << secs.str() << std::setw(12)
                  << (j.size ? stages::format_bytes(double(j.size)) : "-") << terminal_safe(j.note)
                  << "\n";
      }
      std::cout << baked << " baked, " << fresh << " up to date, " << failed << " failed in "
                << std::fixed << std::setprecision(2) << wall << " s\n";
    }
    return failed ? int(ExitCode::Input) : 0;
  };
}

const bool batch_registered = register_command(
    {"batch", "Bake a folder or list of fabrics: up-to-date skips, parallel, farm scripts",
     setup_batch});

}  // namespace
}  // namespace clothbake::cli

// The engine of `clothbake batch` (docs/batch.md, "Batch" and "Slurm"): the list of fabrics, the
// up-to-date check against each fabric's stamp (batch_stamp.hpp), the scheduler that runs one
// `clothbake bake` child process per fabric within a job count and a memory bound, and the Slurm
// job array written instead of baking. cmd_batch.cpp parses the options and prints the results.
//
// C++20, POSIX (posix_spawn, waitpid). Errors: clothbake::Error(Input) naming the file for a list
// that cannot be read or names no fabric and for an output folder that cannot be created; a
// fabric that cannot be baked is not an error here but a job with status "failed" and a note.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace clothbake::cli {

// The peak memory assumed for a bake that was never measured: 2 GiB.
inline constexpr uint64_t kUnknownPeakBytes = uint64_t(2) << 30;

struct BatchOptions {
  std::string source;      // folder of fabric .toml files, or a list file (one path per line)
  std::string output_dir;  // OUTDIR/<fabric stem>.cbk; state in OUTDIR/.clothbake-batch
  int jobs = 1;            // bakes at once; 0: one per core
  std::string cache;       // --cache of every bake (empty: $CLOTHBAKE_CACHE or none)
  std::string cache_max_size;
  std::string scene;   // every bake bakes its plan for this scene (`bake --scene`)
  bool force = false;  // bake up-to-date fabrics too
  // The clothbake executable the bakes run (empty: the running one, current_executable()); tests
  // set a stand-in.
  std::string executable;
};

struct BatchJob {
  std::string fabric;  // path as listed (relative paths resolved against the list's folder)
  std::string name;    // stem: OUTDIR/<name>.cbk
  std::string output;
  std::string status = "pending";  // then running, baked, up-to-date or failed
  std::string note;
  double seconds = 0;
  uint64_t size = 0;
  uint64_t peak = 0;  // measured (stamp or this run), 0 unknown
  pid_t pid = -1;
  std::chrono::steady_clock::time_point start;
};

// The jobs of o.source in order (a folder's *.toml sorted by path; a list's non-empty lines that
// are not # comments, at most 16 MiB of list). A job whose output another job also maps to, or
// whose fabric is not a regular file, is "failed" with a note naming why; the others "pending".
std::vector<BatchJob> list_batch_jobs(const BatchOptions& o);

// Creates OUTDIR/.clothbake-batch, then marks each pending job whose stamp holds "up-to-date"
// (unless o.force), filling its measured peak and size; the others get the stamp check's reason as
// their note ("never baked", "PATH changed", ...; empty for an up-to-date fabric that o.force
// bakes again). Returns the peak to assume for a job never measured: the largest measured peak of
// the list, or kUnknownPeakBytes. Error(Input) when the folder cannot be created.
uint64_t check_batch_stamps(const BatchOptions& o, std::vector<BatchJob>& jobs);

struct SlurmScript {
  std::string script;  // OUTDIR/clothbake-batch.sbatch (executable)
  std::string list;    // OUTDIR/clothbake-batch.list: the pending fabrics, absolute, one a line
  std::size_t tasks = 0;
  uint64_t mem_mb = 0;  // per task: peak_estimate + 25 % + 64 MiB
  int cpus_per_task = 0;
};

// Writes the sbatch job array of the pending jobs and its list, both atomically: one task per job,
// running the `clothbake bake` a local batch runs (same executable, cache, cache bound and scene),
// except that a task names its output after the fabric's file name without a final ".toml" (a
// local batch: without its last extension, the same for *.toml). Error(Input) when they cannot be
// written.
SlurmScript write_slurm_script(const BatchOptions& o, const std::vector<BatchJob>& jobs,
                               uint64_t peak_estimate);

struct BatchRun {
  int at_once = 1;           // bakes at once
  int threads_per_bake = 1;  // cores / at_once
  double wall_seconds = 0;
};

// Bakes the pending jobs: in list order, first fit by memory (the running bakes' peaks plus 10 %,
// or unknown_peak, never above max_memory, except that one bake always may run), at most o.jobs at
// once (0: one per core), each a child process `EXECUTABLE bake FABRIC -o OUTPUT --quiet
// --threads T --report R [--cache ...] [--scene ...]` with stdout to /dev/null and stderr to
// OUTDIR/.clothbake-batch/<name>.log. Each pending job ends "baked" (its report read, its stamp
// written) or "failed" with a note: the last line of its log, "killed by signal N", "cannot start
// clothbake", "baked, but the report or stamp failed: ..." or, should waiting for children fail,
// "lost track of the bake". on_start(to_bake, at_once) is called once before; on_end(job, ended,
// to_bake) as each started bake ends (not for one that could not start). Waits for any child of
// the process (waitpid(-1)): the caller must have no other children of its own.
BatchRun run_batch(const BatchOptions& o, std::vector<BatchJob>& jobs, uint64_t max_memory,
                   uint64_t unknown_peak,
                   const std::function<void(std::size_t to_bake, int at_once)>& on_start = {},
                   const std::function<void(const BatchJob&, std::size_t ended,
                                            std::size_t to_bake)>& on_end = {});

}  // namespace clothbake::cli

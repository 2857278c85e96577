// The engine of `clothbake batch` (batch_run.hpp).
#include "bake/cli/batch_run.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "bake/cache/stage_cache.hpp"
#include "bake/cli/batch_stamp.hpp"
#include "bake/cli/depfile.hpp"
#include "bake/inputs/fabric_files.hpp"
#include "common/child_process.hpp"
#include "common/error.hpp"
#include "common/version.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::cli {
namespace {
namespace fs = std::filesystem;

// Largest fabric list read: 16 MiB (some 100 000 paths); checked before reading.
constexpr std::size_t kMaxListBytes = std::size_t(16) << 20;

std::string state_dir(const BatchOptions& o) {
  return (fs::path(o.output_dir) / ".clothbake-batch").string();
}

// Options that change the bytes of an asset (part of the up-to-date key).
std::string options_key(const BatchOptions& o) {
  // The scene's content is an input of the stamp (the bake report lists it); its path is here.
  return o.scene.empty() ? "bake defaults" : "bake --scene " + fs::absolute(o.scene).string();
}

std::string executable(const BatchOptions& o) {
  return o.executable.empty() ? current_executable() : o.executable;
}

std::string stamp_file(const BatchOptions& o, const BatchJob& j) {
  return (fs::path(state_dir(o)) / (j.name + ".stamp.json")).string();
}

StampKey stamp_key(const BatchOptions& o, const BatchJob& j) {
  return {CLOTHBAKE_VERSION_STRING, executable(o), options_key(o), j.fabric, j.output};
}

// Up to date: the fabric's stamp holds (batch_stamp.hpp). Fills j.peak and j.size.
bool up_to_date(const BatchOptions& o, BatchJob& j, std::string* why) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(stamp_file(o, j), ec))) {
    *why = "never baked";
    return false;
  }
  StampCheck check;
  try {  // a stamp that is not a regular file of bounded size reads as unreadable
    check = check_stamp(inputs::read_file_bytes(stamp_file(o, j), "stamp", kMaxListBytes),
                        stamp_key(o, j));
  } catch (const Error&) {
    check.why = "unreadable stamp";
  }
  j.peak = check.peak_rss_bytes;
  j.size = check.output_size;
  *why = check.why;
  return check.up_to_date;
}

void write_stamp(const BatchOptions& o, const BatchJob& j, const nlohmann::json& report) {
  formats::write_text_atomically(
      stamp_file(o, j),
      make_stamp(stamp_key(o, j), o.scene.empty() ? "" : fs::absolute(o.scene).string(), report));
}

std::vector<std::string> bake_arguments(const BatchOptions& o, const BatchJob& j, int threads,
                                        const std::string& report) {
  std::vector<std::string> args = {
      "bake",     j.fabric, "-o", j.output, "--quiet", "--threads", std::to_string(threads),
      "--report", report};
  const std::string cache = cache::cache_dir_from(o.cache);
  if (!cache.empty()) args.insert(args.end(), {"--cache", cache});
  if (!o.cache_max_size.empty()) args.insert(args.end(), {"--cache-max-size", o.cache_max_size});
  if (!o.scene.empty()) args.insert(args.end(), {"--scene", fs::absolute(o.scene).string()});
  return args;
}

std::string last_line(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  const std::string prefix = "clothbake: ";
  if (last.rfind(prefix, 0) == 0) last = last.substr(prefix.size());
  return last.empty() ? "failed without a message" : last;
}

std::string sh_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s)
    out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

std::vector<BatchJob> list_batch_jobs(const BatchOptions& o) {
  std::vector<std::string> fabrics;
  std::error_code ec;
  if (fs::is_directory(o.source, ec)) {
    for (const auto& e : fs::directory_iterator(o.source, ec))
      if (e.path().extension() == ".toml") fabrics.push_back(e.path().string());
    if (ec) throw_input_error("cannot list " + o.source + ": " + ec.message());
    std::sort(fabrics.begin(), fabrics.end());
  } else {
    // A regular file of bounded size: a FIFO, /dev/zero or a device is refused at once.
    std::istringstream in(inputs::read_file_bytes(o.source, "fabric list", kMaxListBytes));
    const fs::path base = fs::path(o.source).parent_path();
    std::string line;
    while (std::getline(in, line)) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      line = line.substr(first, line.find_last_not_of(" \t\r") - first + 1);
      fabrics.push_back(fs::path(line).is_absolute() ? line : (base / line).string());
    }
  }
  if (fabrics.empty()) throw_input_error(o.source + " names no fabric (.toml)");
  std::vector<BatchJob> jobs;
  std::map<std::string, std::vector<std::size_t>> by_output;
  for (const auto& f : fabrics) {
    BatchJob j;
    j.fabric = f;
    j.name = fs::path(f).stem().string();
    j.output = (fs::path(o.output_dir) / (j.name + ".cbk")).string();
    by_output[j.output].push_back(jobs.size());
    jobs.push_back(j);
  }
  for (auto& [output, indices] : by_output)
    if (indices.size() > 1)
      for (std::size_t i : indices) {
        std::string others;
        for (std::size_t k : indices)
          if (k != i) others += (others.empty() ? "" : ", ") + jobs[k].fabric;
        jobs[i].status = "failed";
        jobs[i].note = "two fabrics map to " + output + ": also " + others + " (rename one)";
      }
  for (auto& j : jobs) {
    if (j.status != "pending") continue;
    try {  // a missing file, a directory, a FIFO or device: each named as what it is
      inputs::require_regular_file(j.fabric);
    } catch (const Error& e) {
      j.status = "failed";
      j.note = e.what();
    }
  }
  return jobs;
}

uint64_t check_batch_stamps(const BatchOptions& o, std::vector<BatchJob>& jobs) {
  std::error_code ec;
  fs::create_directories(state_dir(o), ec);
  if (ec)
    throw_input_error("cannot create the output folder " + o.output_dir + ": " + ec.message());
  uint64_t known_peak = 0;
  for (auto& j : jobs) {
    if (j.status != "pending") continue;
    std::string why;
    if (up_to_date(o, j, &why) && !o.force) {
      j.status = "up-to-date";
      j.note = "inputs, options and output unchanged";
    } else {
      j.note = why;
    }
    known_peak = std::max(known_peak, j.peak);
  }
  return known_peak ? known_peak : kUnknownPeakBytes;
}

SlurmScript write_slurm_script(const BatchOptions& o, const std::vector<BatchJob>& jobs,
                               uint64_t peak_estimate) {
  std::vector<const BatchJob*> todo;
  for (const auto& j : jobs)
    if (j.status == "pending") todo.push_back(&j);
  const fs::path dir = fs::absolute(o.output_dir);
  const std::string list = (dir / "clothbake-batch.list").string();
  const std::string script = (dir / "clothbake-batch.sbatch").string();
  std::string list_text;
  for (const BatchJob* j : todo)
    list_text += fs::absolute(j->fabric).string() + "\n";
  const int cpus = std::max(1, int(std::thread::hardware_concurrency()));
  const uint64_t mem_mb = (peak_estimate + peak_estimate / 4) / (1 << 20) + 64;  // +25 % margin
  const std::string cache = cache::cache_dir_from(o.cache);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Written by `clothbake batch --emit slurm` (docs/batch.md). One array task per fabric of\n"
    << "# " << list << "; each runs the same stateless, deterministic `clothbake bake` as a local\n"
    << "# batch, so the assets are byte-identical to local bakes.\n"
    << "#SBATCH --job-name=clothbake-batch\n"
    << "#SBATCH --array=0-" << (todo.empty() ? 0 : todo.size() - 1) << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "#SBATCH --mem=" << mem_mb << "M\n"
    << "#SBATCH --output=" << (dir / ".clothbake-batch" / "slurm-%A_%a.log").string() << "\n"
    << "set -euo pipefail\n"
    << "CLOTHBAKE=" << sh_quote(executable(o)) << "\n"
    << "LIST=" << sh_quote(list) << "\n"
    << "OUTDIR=" << sh_quote(dir.string()) << "\n"
    << "FABRIC=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" \"$LIST\")\n"
    << "NAME=$(basename \"$FABRIC\" .toml)\n"
    << "exec \"$CLOTHBAKE\" bake \"$FABRIC\" -o \"$OUTDIR/$NAME.cbk\" --quiet \\\n"
    << "  --threads \"${SLURM_CPUS_PER_TASK:-1}\" --report "
       "\"$OUTDIR/.clothbake-batch/$NAME.report.json\"";
  if (!cache.empty()) s << " \\\n  --cache " << sh_quote(fs::absolute(cache).string());
  if (!o.cache_max_size.empty()) s << " \\\n  --cache-max-size " << sh_quote(o.cache_max_size);
  if (!o.scene.empty()) s << " \\\n  --scene " << sh_quote(fs::absolute(o.scene).string());
  s << "\n";
  formats::write_text_atomically(list, list_text);
  formats::write_text_atomically(script, s.str());
  ::chmod(script.c_str(), 0755);
  SlurmScript out;
  out.script = script;
  out.list = list;
  out.tasks = todo.size();
  out.mem_mb = mem_mb;
  out.cpus_per_task = cpus;
  return out;
}

BatchRun run_batch(
    const BatchOptions& o, std::vector<BatchJob>& jobs, uint64_t max_memory, uint64_t unknown_peak,
    const std::function<void(std::size_t to_bake, int at_once)>& on_start,
    const std::function<void(const BatchJob&, std::size_t ended, std::size_t to_bake)>& on_end) {
  const int cpus = std::max(1, int(std::thread::hardware_concurrency()));
  const int at_once = o.jobs == 0 ? cpus : o.jobs;  // --jobs 0: one bake per core
  const int threads = std::max(1, cpus / at_once);
  auto estimate = [&](const BatchJob& j) { return j.peak ? j.peak + j.peak / 10 : unknown_peak; };
  std::map<pid_t, std::size_t> running;
  uint64_t reserved = 0;
  const auto batch_start = std::chrono::steady_clock::now();
  std::size_t to_bake = 0, ended = 0;
  for (const BatchJob& j : jobs)
    to_bake += j.status == "pending";
  if (on_start) on_start(to_bake, at_once);
  for (;;) {
    // Start what fits: in list order, first fit by memory; one bake always may run.
    for (std::size_t i = 0; i < jobs.size() && int(running.size()) < at_once; ++i) {
      BatchJob& j = jobs[i];
      if (j.status != "pending") continue;
      if (!running.empty() && reserved + estimate(j) > max_memory) continue;
      const std::string base = (fs::path(state_dir(o)) / j.name).string();
      // stdout to /dev/null, stderr to the log (common/child_process.hpp).
      j.pid = spawn_program(executable(o), bake_arguments(o, j, threads, base + ".report.json"),
                            "/dev/null", base + ".log")
                  .pid;
      j.start = std::chrono::steady_clock::now();
      if (j.pid < 0) {
        j.status = "failed";
        j.note = "cannot start clothbake";
        continue;
      }
      j.status = "running";
      running[j.pid] = i;
      reserved += estimate(j);
    }
    if (running.empty()) break;
    const ChildEnd reaped = wait_any_child();  // EINTR retried
    const pid_t pid = reaped.pid;
    const int status = reaped.status;
    if (pid < 0) {
      // Not expected while our children run (ECHILD would mean someone else reaped them).
      const std::string why = std::strerror(reaped.error);
      for (auto& [child, index] : running) {
        jobs[index].status = "failed";
        jobs[index].note = "lost track of the bake (waitpid: " + why + ")";
      }
      break;
    }
    auto it = running.find(pid);
    if (it == running.end()) continue;
    BatchJob& j = jobs[it->second];
    running.erase(it);
    reserved -= estimate(j);
    j.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - j.start).count();
    const std::string base = (fs::path(state_dir(o)) / j.name).string();
    if (child_succeeded(status)) {
      try {
        std::ifstream in(base + ".report.json");
        const nlohmann::json report = nlohmann::json::parse(in);
        j.peak = json_unsigned(report["total"]["peak_rss_bytes"], "total.peak_rss_bytes");
        j.size = json_unsigned(report["asset"]["size_bytes"], "asset.size_bytes");
        j.status = "baked";
        j.note = report["asset"].value("unchanged", false) ? "same bytes (file kept)" : j.note;
        write_stamp(o, j, report);
      } catch (const std::exception& e) {
        j.status = "failed";
        j.note = std::string("baked, but the report or stamp failed: ") + e.what();
      }
    } else {
      j.status = "failed";
      j.note = child_signal(status) != 0 ? describe_wait_status(status)  // "killed by signal N"
                                         : last_line(base + ".log");
    }
    ++ended;
    if (on_end) on_end(j, ended, to_bake);
  }
  BatchRun run;
  run.at_once = at_once;
  run.threads_per_bake = threads;
  run.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_start).count();
  return run;
}

}  // namespace clothbake::cli

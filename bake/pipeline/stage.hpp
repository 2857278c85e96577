// Pipeline stages: pure functions from named input artifacts to named output artifacts, which the
// driver (driver.hpp) runs in dependency order (docs/pipeline.md). The bake's own stages are
// defined in bake/stages/ and listed there in run order (bake/stages/stages.hpp); this folder
// knows none of them.
//
// Conventions: artifacts named "section/<stage>" hold std::vector<formats::Section> and end up in
// the asset; "metadata/<stage>" hold nlohmann::json stored under "parameters"."<stage>" in the
// asset's metadata. Every stage must be deterministic: same inputs, same outputs, whatever the
// thread count (use TBB with a fixed partition of the work and an ordered reduction).
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "bake/pipeline/artifacts.hpp"

namespace clothbake::pipeline {

class StageContext;

struct Stage {
  std::string name;  // [a-z0-9_]+, unique
  std::string description;
  std::vector<std::string> inputs;   // artifacts it needs (their producers run first)
  std::vector<std::string> outputs;  // artifacts it must produce
  // Optional inputs: every artifact whose name starts with one of these prefixes and that a
  // selected stage produces. Their producers run first but are not pulled in by this stage.
  std::vector<std::string> collects;
  // Runs whether or not it is picked with --stages (the asset writer).
  bool always = false;
  std::function<void(StageContext&)> run;
  // The content-keyed cache (RunOptions::cache, docs/batch.md). A cacheable stage's outputs are a
  // pure function of its inputs: they may be kept under a key derived from the inputs and reused.
  // False for stages that read or write files (load_fabric, write).
  bool cacheable = true;
  // Optional, for a stage that reads only part of an input: puts a stand-in holding just that part
  // into `view` under the input's name (e.g. the fabric without its colours, for the stages that
  // albedos do not affect). The cache keys the stage on the stand-in's content instead of the
  // whole input; the stage itself still runs on the real input.
  std::function<void(const Artifacts& available, Artifacts& view)> key_view;
};

// Measurements of one finished stage.
struct StageReport {
  std::string name;
  double wall_seconds = 0;
  double cpu_seconds = 0;       // process CPU time (all threads) spent during the stage
  uint64_t peak_rss_bytes = 0;  // peak resident memory during the stage (see peak_scope)
  std::string peak_scope;       // "stage" (peak reset before the stage) or "process"
  std::string cache;            // "hit", "miss" (ran, stored), "uncached" (ran); "" without cache
};

// Thrown (through a stage reading a deferred input) when a cache entry fails its checksum: the
// entry is gone and run_pipeline runs the stages again, recomputing it.
struct CacheEntryCorrupt : Error {
  explicit CacheEntryCorrupt(const std::string& message) : Error(ExitCode::Input, message) {}
};

// Thrown when values a run took from the cache fail a check that values from a file would fail too
// (a stage refuses an input, the asset assembled from them does not validate): run_pipeline has the
// cache remove the entries it answered from (StageCache::discard_hits) and runs again.
struct CachedValuesInvalid : Error {
  explicit CachedValuesInvalid(const std::string& message) : Error(ExitCode::Input, message) {}
};

// Where finished stage outputs are kept by key (implemented in bake/cache). The driver calls
// load() before a stage and, when it returns false, runs the stage and calls store().
class StageCache {
 public:
  virtual ~StageCache() = default;
  // Fills `produced` with every output of `stage` and returns true when a valid entry exists for
  // the stage's key over `available`; false otherwise (it may then hold a lock on the key until
  // store(), so that concurrent bakes compute a stage once).
  virtual bool load(const Stage& stage, const Artifacts& available, Artifacts& produced) = 0;
  // Keeps the outputs of a stage that ran. Returns false when they were not kept (the stage has
  // no key or an output has no serialiser, or the cache cannot be written: warned once).
  virtual bool store(const Stage& stage, const Artifacts& available, const Artifacts& produced) = 0;
  // Removes every entry load() answered from since the last call, warning for each that it is
  // corrupt (`why`), so that a run after CachedValuesInvalid recomputes them. Returns false when
  // there was none (the failure was then not the cache's).
  virtual bool discard_hits(const std::string& why) {
    (void)why;
    return false;
  }
  // A pipeline run starts (run_pipeline calls it before each run, a retry included): whatever the
  // cache memoised about the previous run's artifacts no longer holds, since the same names may now
  // hold other values (the next fabric of a scene).
  virtual void begin_run() {}
};

struct RunOptions {
  int threads = 0;              // 0: TBB's default (all cores)
  bool show_progress = false;   // progress bar on stderr
  bool record_timings = false;  // stages may store the timings in their outputs (write stage)
  StageCache* cache = nullptr;  // optional: reuse finished stage outputs by key
  // Optional, for library callers (the Python module's bake): called with the running stage's name
  // and its fraction done, in [0, 1]: (name, 0) before the stage runs or is read from the cache,
  // the stage's own StageContext::progress reports in between, (name, 1) after it. The reports
  // come from whichever thread makes them (a stage's TBB workers included), unserialised and
  // unthrottled, and may arrive out of order within a stage. An exception it throws ends the run
  // like the stage's own error (from a worker, TBB carries it to the run's thread): nothing is
  // written at the output.
  std::function<void(const std::string& stage, double fraction)> progress;
};

// What a running stage sees. Reading an undeclared input or producing an undeclared output is an
// internal error: the declarations are the stage's contract.
class StageContext {
 public:
  StageContext(const Stage& stage, const Artifacts& available, Artifacts& produced,
               const RunOptions& options, const std::vector<std::string>& order,
               const std::vector<StageReport>& completed, std::function<void(double)> progress);

  template <class T>
  const T& input(const std::string& name) const {
    check_readable(name);
    return available_.get<T>(name);
  }
  bool has_input(const std::string& name) const;
  // Collected artifacts with this prefix (one of Stage::collects), sorted by name.
  std::vector<std::string> collected(const std::string& prefix) const;

  template <class T>
  void output(const std::string& name, T value) {
    check_writable(name);
    produced_.put(name, std::move(value));
  }

  // Fraction of this stage done, in [0, 1]. Thread-safe, cheap (call it often).
  void progress(double fraction) const {
    if (progress_) progress_(fraction);
  }

  const Stage& stage() const { return stage_; }
  const RunOptions& options() const { return options_; }
  // Names of the stages of this run in execution order, and the reports of the finished ones.
  const std::vector<std::string>& stage_order() const { return order_; }
  const std::vector<StageReport>& completed() const { return completed_; }

 private:
  void check_readable(const std::string& name) const;
  void check_writable(const std::string& name) const;

  const Stage& stage_;
  const Artifacts& available_;
  Artifacts& produced_;
  const RunOptions& options_;
  const std::vector<std::string>& order_;
  const std::vector<StageReport>& completed_;
  std::function<void(double)> progress_;
};

}  // namespace clothbake::pipeline

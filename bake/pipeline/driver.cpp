#include "bake/pipeline/driver.hpp"

#include <tbb/global_control.h>

#include <memory>
#include <set>

#include "bake/pipeline/plan.hpp"
#include "bake/pipeline/progress.hpp"
#include "bake/pipeline/resource_usage.hpp"

namespace clothbake::pipeline {

namespace {

RunResult run_once(const std::vector<std::string>& picked, Artifacts seeded,
                   const RunOptions& options, const std::vector<Stage>& stages) {
  const auto seeded_names = seeded.names();
  const std::vector<const Stage*> plan =
      plan_stages(stages, picked, std::set<std::string>(seeded_names.begin(), seeded_names.end()));

  std::unique_ptr<tbb::global_control> thread_limit;
  if (options.threads > 0)
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, std::size_t(options.threads));

  RunResult result;
  result.threads =
      int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  result.artifacts = std::move(seeded);
  std::vector<std::string> order;
  for (const Stage* s : plan)
    order.push_back(s->name);

  ProgressBar bar(options.show_progress);
  bool cache_hits = false;  // values from the cache are checked like values from a file
  const double run_wall = wall_seconds();
  const double run_cpu = process_cpu_seconds();
  for (std::size_t i = 0; i < plan.size(); ++i) {
    const Stage& stage = *plan[i];
    bar.begin_stage(int(i), int(plan.size()), stage.name);
    Artifacts produced;
    if (options.progress) options.progress(stage.name, 0.0);
    StageContext context(stage, result.artifacts, produced, options, order, result.stages,
                         [&bar, &options, &stage](double f) {
                           bar.update(f);
                           if (options.progress) options.progress(stage.name, f);
                         });
    StageReport report;
    report.name = stage.name;
    report.peak_scope = reset_peak_rss() ? "stage" : "process";
    const double wall0 = wall_seconds();
    const double cpu0 = process_cpu_seconds();
    if (options.cache == nullptr) {
      stage.run(context);
    } else if (options.cache->load(stage, result.artifacts, produced)) {
      report.cache = "hit";
      cache_hits = true;
    } else {
      try {
        stage.run(context);
      } catch (const CacheEntryCorrupt&) {
        throw;
      } catch (const CachedValuesInvalid&) {
        throw;
      } catch (const Error& e) {
        // A computing stage refuses only what it was given: after cache hits, the cached values.
        if (e.code() != ExitCode::Input || !cache_hits || !stage.cacheable) throw;
        throw CachedValuesInvalid("the " + stage.name + " stage refused them: " + e.what());
      }
      report.cache = options.cache->store(stage, result.artifacts, produced) ? "miss" : "uncached";
    }
    report.wall_seconds = wall_seconds() - wall0;
    report.cpu_seconds = process_cpu_seconds() - cpu0;
    report.peak_rss_bytes = peak_rss_bytes();
    for (const auto& out : stage.outputs) {
      if (!produced.contains(out))
        throw_internal_error("stage '" + stage.name + "' did not produce its output '" + out + "'");
      result.artifacts.take(produced, out);
    }
    result.stages.push_back(report);
    if (options.progress) options.progress(stage.name, 1.0);
  }
  bar.finish();
  result.wall_seconds = wall_seconds() - run_wall;
  result.cpu_seconds = process_cpu_seconds() - run_cpu;
  result.peak_rss_bytes = 0;
  for (const auto& s : result.stages)
    result.peak_rss_bytes = std::max(result.peak_rss_bytes, s.peak_rss_bytes);
  return result;
}

}  // namespace

RunResult run_pipeline(const std::vector<std::string>& picked, Artifacts seeded,
                       const RunOptions& options, const std::vector<Stage>& stages) {
  // A corrupt cache entry found while a stage reads it has been removed: run again (each retry
  // removes one entry, so this ends; three are plenty in practice). Values from the cache that
  // fail a later check: their entries are removed, and the run again recomputes them.
  for (int attempt = 0;; ++attempt) {
    if (options.cache != nullptr) options.cache->begin_run();
    try {
      return run_once(picked, seeded, options, stages);
    } catch (const CacheEntryCorrupt&) {
      if (options.cache == nullptr || attempt >= 8) throw;
    } catch (const CachedValuesInvalid& e) {
      if (options.cache == nullptr || attempt >= 8 || !options.cache->discard_hits(e.what())) throw;
    }
  }
}

}  // namespace clothbake::pipeline

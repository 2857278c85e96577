// Runs pipeline stages in dependency order with a fixed thread budget, measuring each stage.
#pragma once

#include <string>
#include <vector>

#include "bake/pipeline/artifacts.hpp"
#include "bake/pipeline/stage.hpp"

namespace clothbake::pipeline {

struct RunResult {
  std::vector<StageReport> stages;  // in execution order
  double wall_seconds = 0;
  double cpu_seconds = 0;
  uint64_t peak_rss_bytes = 0;  // process peak at the end of the run
  int threads = 0;              // effective TBB parallelism
  Artifacts artifacts;          // the seeded artifacts and everything the stages produced
};

// Plans (plan_stages) and runs `stages`: the `picked` ones (empty: all), with `seeded` artifacts
// available from the start. options.threads > 0 caps TBB's parallelism for the whole run
// (tbb::global_control). Errors thrown by a stage propagate unchanged; a stage that does not
// produce a declared output is an Error(Internal). A bake passes stages::bake_stages().
RunResult run_pipeline(const std::vector<std::string>& picked, Artifacts seeded,
                       const RunOptions& options, const std::vector<Stage>& stages);

}  // namespace clothbake::pipeline

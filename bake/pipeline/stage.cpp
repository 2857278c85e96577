#include <algorithm>

#include "bake/pipeline/stage.hpp"

namespace clothbake::pipeline {
StageContext::StageContext(const Stage& stage, const Artifacts& available, Artifacts& produced,
                           const RunOptions& options, const std::vector<std::string>& order,
                           const std::vector<StageReport>& completed,
                           std::function<void(double)> progress)
    : stage_(stage),
      available_(available),
      produced_(produced),
      options_(options),
      order_(order),
      completed_(completed),
      progress_(std::move(progress)) {}

bool StageContext::has_input(const std::string& name) const {
  check_readable(name);
  return available_.contains(name);
}

std::vector<std::string> StageContext::collected(const std::string& prefix) const {
  if (std::find(stage_.collects.begin(), stage_.collects.end(), prefix) == stage_.collects.end())
    throw_internal_error("stage '" + stage_.name + "' collects no artifacts named '" + prefix +
                         "*'");
  return available_.names(prefix);
}

void StageContext::check_readable(const std::string& name) const {
  if (std::find(stage_.inputs.begin(), stage_.inputs.end(), name) != stage_.inputs.end()) return;
  for (const auto& prefix : stage_.collects)
    if (name.compare(0, prefix.size(), prefix) == 0) return;
  throw_internal_error("stage '" + stage_.name + "' reads artifact '" + name +
                       "' that it does not declare as an input");
}

void StageContext::check_writable(const std::string& name) const {
  if (std::find(stage_.outputs.begin(), stage_.outputs.end(), name) == stage_.outputs.end())
    throw_internal_error("stage '" + stage_.name + "' produces artifact '" + name +
                         "' that it does not declare as an output");
}

}  // namespace clothbake::pipeline

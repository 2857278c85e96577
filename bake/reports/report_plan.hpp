// `clothbake report plan SCENE.toml -o DIR`: the proof that a scene-planned bake does not change
// the picture (docs/scene-plans.md, "Proof"). For every fabric the scene's objects name, bakes the
// full asset and the planned one (timed, this machine, this run), renders the scene twice with each
// (same method and spp; two seeds, each shared by a full and a planned render) and once with the
// Reference method on the full assets, and writes the relMSE between the expected planned and full
// renders (unbiased, from the two pairs), of both against the reference over that fabric's
// pixels, the sizes and bake times, DIR/plan.json, DIR/side-by-side.png (full | planned |
// difference map); returns the JSON document and a summary for the command to print, with a
// failure (exit 5) when a fabric's planned render is over the scene's budget: relMSE planned vs
// full > [render] max_error (the relative RMS is reported beside it, docs/scene-plans.md says why
// it is not the criterion). With --image-size the plan is made for that size (footprints and view
// directions change with it).
#pragma once

#include "bake/reports/report_output.hpp"

#include <cstdint>
#include <string>

namespace clothbake::reports {

struct PlanReportOptions {
  std::string scene, output;
  uint32_t spp = 2;
  uint64_t seed = 1;
  int width = 0, height = 0;    // > 0: render at this size instead of the scene camera's
  uint32_t reference_spp = 64;  // light samples of the reference with environment lights
};

// Throws Error: Usage for bad options (naming the option), Input for a bad scene, fabric or
// output. A planned render over the budget is ReportOutput::failure, after writing everything.
ReportOutput plan_report(const PlanReportOptions& options);

}  // namespace clothbake::reports

// `clothbake report error-time SCENE.toml -o DIR`: renders the scene's reference (the exact
// footprint integrals) and its path-traced truth (brute-path converged) once each (cached by
// content), then every method over an spp sweep, timing each render's wall time on this machine in
// this run; writes DIR/error-time.csv, error-time.json (rows, and per method pair the equal-error
// speedup and the equal-time error ratio), error-time.png/.svg and grid.png (via
// scripts/plot_error_time.py); returns the JSON document and a summary for the command to print
// (docs/rendering.md, "Error against run time").
#pragma once

#include "bake/reports/report_output.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace clothbake::reports {

struct ErrorTimeOptions {
  std::string scene, output, cache;
  // brute-path: brute force path-traced (render::RenderOptions::path_traced), as a renderer without
  // a multi-scale model pays it: a camera ray, a hit and shadow rays per sample.
  std::vector<std::string> methods = {"multiscale", "multiscale-paper", "brute", "brute-path"};
  std::vector<uint32_t> spp = {1, 2, 4, 8, 16, 32, 64, 128, 256};
  uint32_t reference_spp = 256;  // light samples of the reference with environment lights
  // The path-traced truth: brute-path at this many spp (two independent halves, to remove its own
  // noise from the errors); 0 skips it. Even.
  uint32_t truth_spp = 1024;
  int width = 0, height = 0;  // > 0: render at this size instead of the scene camera's
  uint64_t seed = 1;
  bool no_plots = false;
  bool quiet = false;  // no progress bar and no baking messages on stderr (`--json`)
  // Also ray-trace the first cloth plane's real relief and report the error of the parallax-offset
  // model and of the model without offsets against it (paper Fig. 6).
  bool near_field = false;
  uint32_t near_field_samples = 4;  // s x s sub-pixel rays of the ray-traced reference
  // Also render the multi-scale methods with the raw and with the compressed tables of assets that
  // hold both (objects given as `fabric =` are baked with --keep-raw into the cache for it), and
  // report what the compression changes.
  bool raw_tables = false;
};

// Throws Error(Usage) for bad options (naming the option), Error(Input) for a bad scene or output.
ReportOutput error_time_report(const ErrorTimeOptions& options);

}  // namespace clothbake::reports

// How good is one ASG per texel on real weaves, and how good is our fit? (docs/raycast.md, "ASG
// fit: measured quality"). Not a benchmark: a study program that prints a table.
//
//   build-*/bin/asg_fit_study [RESOLUTION=64] [FABRIC.toml ...]
//
// For each fabric (default: the example plain, twill and satin), samples the visibility of every
// texel on the 32 x 32 hemisphere grid and fits it four ways:
//   bake     : the production fit (raycast/asg_fit.hpp, default options);
//   long     : the same starts with 64 Levenberg-Marquardt steps instead of 8;
//   restarts : plus 24 random starts, each refined by 64 steps, best kept (an estimate of the best
//              single lobe this model can reach);
//   xu       : Xu et al.'s ASG with the smooth term max(v.z, 0), fitted like `restarts`;
// and prints the mean and 90th percentile of the RMS error, the baseline of the best constant
// (sqrt(f (1 - f)) for a visible fraction f), and the time per texel of each.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bake/inputs/fabric_load.hpp"
#include "raycast/asg_fit.hpp"
#include "raycast/visibility.hpp"

using namespace clothbake;

namespace {

struct Column {
  const char* name;
  raycast::AsgFitOptions options;
  std::vector<double> errors;
  double seconds = 0;
};

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, std::size_t(p * double(v.size())))];
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v)
    s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

}  // namespace

int main(int argc, char** argv) {
  int resolution = argc > 1 ? std::atoi(argv[1]) : 64;
  std::vector<std::string> fabrics;
  for (int i = 2; i < argc; ++i)
    fabrics.push_back(argv[i]);
  if (fabrics.empty())
    for (const char* name : {"plain", "twill", "satin"})
      fabrics.push_back(std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/" + name + ".toml");

  raycast::VisibilitySettings settings;
  const raycast::FitDirections directions = raycast::visibility_fit_directions(settings.dirs);
  const int dir_count = settings.dirs * settings.dirs;

  std::printf("%-10s %-9s %10s %10s %12s\n", "fabric", "fit", "mean RMS", "p90 RMS", "us/texel");
  for (const std::string& path : fabrics) {
    LoadOptions load;
    load.resolution = resolution;
    Fabric fabric = load_fabric_description(path, load).fabric;
    raycast::VisibilitySamples samples = raycast::sample_visibility(fabric.maps, settings);
    std::vector<Column> columns(4);
    columns[0].name = "bake";
    columns[1].name = "long";
    columns[1].options.max_refinements = 64;
    columns[2].name = "restarts";
    columns[2].options.max_refinements = 64;
    columns[2].options.random_starts = 24;
    columns[3].name = "xu";
    columns[3].options = columns[2].options;
    columns[3].options.xu_smooth_term = true;
    std::vector<double> baseline;
    std::vector<uint8_t> visible(static_cast<std::size_t>(dir_count));
    const std::size_t texels = fabric.maps.texel_count();
    for (std::size_t t = 0; t < texels; ++t) {
      for (int k = 0; k < dir_count; ++k)
        visible[std::size_t(k)] = samples.visible(t, k);
      double f = samples.visible_fraction(t);
      baseline.push_back(std::sqrt(f * (1 - f)));
    }
    for (Column& c : columns) {
      auto start = std::chrono::steady_clock::now();
      for (std::size_t t = 0; t < texels; ++t) {
        for (int k = 0; k < dir_count; ++k)
          visible[std::size_t(k)] = samples.visible(t, k);
        c.errors.push_back(raycast::fit_asg(directions, visible.data(), c.options).rms_error);
      }
      c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    std::string name = path.substr(path.find_last_of('/') + 1);
    for (const Column& c : columns)
      std::printf("%-10s %-9s %10.4f %10.4f %12.1f\n", name.c_str(), c.name, mean(c.errors),
                  percentile(c.errors, 0.9), 1e6 * c.seconds / double(texels));
    std::printf("%-10s %-9s %10.4f %10.4f\n", name.c_str(), "constant", mean(baseline),
                percentile(baseline, 0.9));
  }
  return 0;
}

// The default bake of every example fabric, whole pipeline in process, against the bake targets
// (docs/performance.md, "Bake benchmark"): per-stage wall time, CPU time and peak resident memory
// as counters, and a table on stdout at the end with the targets (twill <= 12 s wall, <= 24 s
// CPU, every bake <= 1 GiB peak, every other example fabric <= 15 s wall).
//   build/bin/bench_bake                                  (every example fabric, ~2 min)
//   build/bin/bench_bake --benchmark_filter=twill         (the default twill bake only)
//   build/bin/bench_bake --benchmark_repetitions=3        (medians of 3)
// The assets go to a temporary directory ($TMPDIR or /tmp) and are removed at the end.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"

namespace {

using namespace clothbake;
namespace fs = std::filesystem;

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

struct Target {
  double wall_s, cpu_s, peak_bytes;
};

// The targets: the twill (the paper's default) and every other example fabric.
Target target_of(const std::string& fabric) {
  if (fabric == "twill") return {12.0, 24.0, kGiB};
  return {15.0, 1e30, kGiB};
}

struct Measured {
  double wall = 0, cpu = 0, peak = 0, asset_bytes = 0;
  std::map<std::string, pipeline::StageReport> stages;
};
std::map<std::string, std::vector<Measured>>& results() {
  static std::map<std::string, std::vector<Measured>> r;
  return r;
}

fs::path scratch() {
  static const fs::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    fs::path d = fs::path(tmp && *tmp ? tmp : "/tmp") /
                 ("clothbake-bench-bake-" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

void BM_DefaultBake(benchmark::State& state, const std::string& fabric) {
  pipeline::BakeRequest request;
  request.fabric_path = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/fabrics/" + fabric + ".toml";
  request.output_path = (scratch() / (fabric + ".cbk")).string();
  request.force = true;
  for (auto _ : state) {
    const pipeline::BakeResult result = pipeline::bake(request, stages::bake_stages());
    Measured m;
    m.wall = result.run.wall_seconds;
    m.cpu = result.run.cpu_seconds;
    m.peak = double(result.run.peak_rss_bytes);
    m.asset_bytes = double(result.asset.size_bytes);
    for (const auto& s : result.run.stages)
      m.stages[s.name] = s;
    state.SetIterationTime(m.wall);
    state.counters["cpu_s"] = m.cpu;
    state.counters["peak_GiB"] = m.peak / kGiB;
    state.counters["asset_MB"] = m.asset_bytes / 1e6;
    for (const auto& s : result.run.stages)
      if (s.wall_seconds > 0.05) state.counters[s.name + "_s"] = s.wall_seconds;
    results()[fabric].push_back(std::move(m));
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

void print_table() {
  std::printf("\nDefault bakes against the targets (median of %s), threads: all cores\n",
              "the repetitions");
  std::printf("%-8s %9s %9s %9s %9s  %s\n", "fabric", "wall s", "CPU s", "peak GiB", "asset MB",
              "target (wall / CPU / peak)");
  for (const auto& [fabric, runs] : results()) {
    std::vector<double> wall, cpu, peak, bytes;
    for (const auto& m : runs) {
      wall.push_back(m.wall);
      cpu.push_back(m.cpu);
      peak.push_back(m.peak);
      bytes.push_back(m.asset_bytes);
    }
    const Target t = target_of(fabric);
    const double w = median(wall), c = median(cpu), p = median(peak);
    const bool ok = w <= t.wall_s && c <= t.cpu_s && p <= t.peak_bytes;
    std::printf("%-8s %9.2f %9.2f %9.3f %9.1f  %s (%.0f s / %s / %.0f GiB)\n", fabric.c_str(), w, c,
                p / kGiB, median(bytes) / 1e6, ok ? "met" : "MISSED", t.wall_s,
                t.cpu_s < 1e29 ? (std::to_string(int(t.cpu_s)) + " s").c_str() : "-",
                t.peak_bytes / kGiB);
    std::printf("         per stage (last run): ");
    for (const auto& [name, s] : runs.back().stages)
      if (s.wall_seconds > 0.05)
        std::printf("%s %.2f/%.2f s %.2f GiB; ", name.c_str(), s.wall_seconds, s.cpu_seconds,
                    double(s.peak_rss_bytes) / kGiB);
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  clothbake::set_quiet(true);  // the bakes' warnings are not what this measures
  for (const char* fabric : {"twill", "plain", "satin", "argyle", "diamond", "voile"})
    benchmark::RegisterBenchmark(("DefaultBake/" + std::string(fabric)).c_str(), BM_DefaultBake,
                                 std::string(fabric))
        ->Iterations(1)
        ->UseManualTime()
        ->Unit(benchmark::kSecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  print_table();
  std::error_code ec;
  fs::remove_all(scratch(), ec);
  return 0;
}

// clothbake bake FABRIC.toml -o OUT.cbk [--stages a,b] [--threads N] [--quiet] [--report R.json]
// [--json] [--force] [--record-timings] [--list-stages]
// [--compress K,R | --max-error E] [--keep-raw] [--no-compress] [--scene SCENE.toml]
// [--max-memory S]: runs the bake pipeline (docs/pipeline.md) and writes one asset atomically,
// after refusing a bake whose estimated peak memory is above --max-memory (default: the machine's
// RAM or cgroup limit) before any map is loaded. By default the asset holds the C-PCA
// compressed Integral-Radiance tables only (docs/compression.md, "Bake"). Exit 2 on bad input, an
// unwritable output or a bake too large for --max-memory (nothing written), 1 on a bad command
// line (unknown stage, conflicting compression options, compression options with --stages that
// leave out the compress stage, a malformed --max-memory).
#include <algorithm>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "bake/cache/stage_cache.hpp"
#include "bake/cli/command.hpp"
#include "bake/cli/depfile.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/pipeline/plan.hpp"
#include "bake/pipeline/progress.hpp"
#include "bake/reports/scene_plan.hpp"
#include "bake/stages/cache_support.hpp"
#include "bake/stages/memory_estimate.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::cli {
namespace {

struct BakeOptions {
  std::string fabric;
  std::string output;
  std::vector<std::string> stages;
  int threads = 0;
  bool quiet = false;
  bool json = false;
  bool force = false;
  bool record_timings = false;
  bool list_stages = false;
  std::string report;
  std::string depfile;
  std::string depfile_target;  // default: the output
  std::string cache;           // --cache DIR (else $CLOTHBAKE_CACHE)
  std::string cache_max_size;  // --cache-max-size
  bool no_cache = false;
  // Compression (compress/compress_settings.hpp).
  std::string compress_shape;  // --compress K,R
  double max_error = 0.0;      // --max-error E
  CLI::Option* max_error_option = nullptr;
  bool keep_raw = false;
  bool no_compress = false;
  std::string scene;              // --scene: bake the scene's plan
  std::optional<int> resolution;  // --resolution: a weave's maps at N texels a side
  std::string max_memory;         // --max-memory S (default: the machine's memory)
};

std::string default_max_error_text() {
  std::ostringstream text;
  text << compress::kDefaultMaxError;  // "0.008", not to_string's "0.008000"
  return text.str();
}

// --compress K,R: C-PCA clusters per visibility cluster K in [1, kMaxCpcaClustersPerStratum] and
// rank R in [0, kMaxCpcaRank]. Throws Error(Usage) naming --compress.
std::pair<int, int> compress_shape(const std::string& text) {
  std::vector<double> v;
  try {
    v = parse_number_list(text, "--compress", {.expected = "K,R", .count = 2, .integers = true});
  } catch (const CLI::ValidationError&) {  // the established message, which scripts may match
    throw Error(ExitCode::Usage,
                "--compress expects K,R (C-PCA clusters per visibility cluster and rank, e.g. "
                "1,24), got '" +
                    text + "'");
  }
  const int clusters = int(v[0]), rank = int(v[1]);
  if (v[0] < 1 || v[0] > compress::kMaxCpcaClustersPerStratum)
    throw Error(ExitCode::Usage, "--compress: K must be in [1, " +
                                     std::to_string(compress::kMaxCpcaClustersPerStratum) +
                                     "], got " + std::to_string(clusters));
  if (v[1] < 0 || v[1] > compress::kMaxCpcaRank)
    throw Error(ExitCode::Usage, "--compress: R must be in [0, " +
                                     std::to_string(compress::kMaxCpcaRank) + "], got " +
                                     std::to_string(rank));
  return {clusters, rank};
}

// The compression request of the command line, checked (Error(Usage) naming the options).
compress::CompressRequest compress_request(const BakeOptions& o) {
  compress::CompressRequest r;
  r.disable = o.no_compress;
  r.keep_raw = o.keep_raw;
  if (!o.compress_shape.empty()) {
    const auto [clusters, rank] = compress_shape(o.compress_shape);
    r.clusters = clusters;
    r.rank = rank;
  }
  if (o.max_error_option && o.max_error_option->count() > 0) r.max_error = o.max_error;
  compress::check_compress_request(r);
  const auto given = r.given();
  if (!given.empty() && !o.stages.empty() &&
      std::find(o.stages.begin(), o.stages.end(), "compress") == o.stages.end())
    throw Error(ExitCode::Usage, given.front() +
                                     " has no effect: --stages does not include the compress "
                                     "stage (add it, or drop " +
                                     given.front() + ")");
  return r;
}

void print_stage_list(bool json) {
  // The explicit list: the order in which a full bake runs the stages.
  const auto list = stages::bake_stages();
  if (json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& s : list)
      out.push_back({{"name", s.name},
                     {"description", s.description},
                     {"inputs", s.inputs},
                     {"outputs", s.outputs},
                     {"collects", s.collects},
                     {"always", s.always}});
    print_json({{"stages", out}});
    return;
  }
  for (const auto& s : list) {
    std::cout << s.name << (s.always ? " (always)" : "") << ": " << s.description << "\n    in:";
    for (const auto& i : s.inputs)
      std::cout << ' ' << i;
    for (const auto& c : s.collects)
      std::cout << ' ' << c << '*';
    std::cout << "\n    out:";
    for (const auto& o : s.outputs)
      std::cout << ' ' << o;
    std::cout << '\n';
  }
  std::cout.flush();
}

Action setup_bake(CLI::App& app) {
  auto o = std::make_shared<BakeOptions>();
  app.add_option("FABRIC", o->fabric, "fabric description (TOML)");
  app.add_option("-o,--output", o->output, "asset to write (.cbk)");
  app.add_option("--stages", o->stages,
                 "comma-separated stages to run (plus the stages they need); default: all")
      ->delimiter(',');
  add_threads_option(app, o->threads, "worker threads (the asset is identical for any N)");
  app.add_flag("--quiet", o->quiet, "no progress bar and no informational messages");
  app.add_option("--report", o->report,
                 "write a JSON report: per-stage wall/CPU time and peak memory, asset sections");
  add_json_flag(app, o->json, "print the report on stdout");
  app.add_option("--depfile", o->depfile,
                 "write a Make-syntax depfile: the output and every file the bake read (fabric, "
                 "maps, WIF, the clothbake executable)");
  app.add_option("--depfile-target", o->depfile_target,
                 "target named in the depfile (default: the output), e.g. a stamp file for Make");
  app.add_flag("--force", o->force, "replace an existing output file that is not an asset");
  app.add_flag("--record-timings", o->record_timings,
               "store stage timings in the asset metadata (makes the bytes differ run to run)");
  app.add_option("--cache", o->cache,
                 "content-keyed cache of finished stage outputs (default: $CLOTHBAKE_CACHE; "
                 "docs/batch.md)");
  app.add_option("--cache-max-size", o->cache_max_size,
                 "bound of the cache, least recently used entries out (default 10G)");
  app.add_flag("--no-cache", o->no_cache, "ignore --cache and $CLOTHBAKE_CACHE");
  app.add_flag("--list-stages", o->list_stages, "list the stages in run order and exit");
  app.add_option("--compress", o->compress_shape,
                 "C-PCA with a fixed shape K,R: K clusters per visibility cluster, rank R "
                 "(default: ranks chosen for the target error, see --max-error)");
  o->max_error_option = app.add_option(
      "--max-error", o->max_error,
      "target relative RMS error of the compressed texels; the stage picks the ranks "
      "(default " +
          default_max_error_text() + ")");
  app.add_flag(
      "--keep-raw", o->keep_raw,
      "also keep the raw Integral-Radiance tables in the asset (default: compressed only)");
  app.add_flag("--no-compress", o->no_compress,
               "write the raw Integral-Radiance tables only (no C-PCA compression)");
  app.add_option("--resolution", o->resolution,
                 "texels per tile side of a weave's maps (default: the fabric's [bake] "
                 "resolution, 256 for a WIF draft); image maps must already have it")
      ->check(CLI::Range(kMinResolution, kMaxResolution));
  app.add_option("--scene", o->scene,
                 "bake only what this scene can query (its plan: `clothbake plan`; "
                 "docs/scene-plans.md)");
  app.add_option("--max-memory", o->max_memory,
                 "refuse (exit 2, before loading the maps) a bake whose estimated peak memory is "
                 "above this size, e.g. 8G (default: the machine's RAM or cgroup limit)");
  return [o] {
    if (o->list_stages) {
      print_stage_list(o->json);
      return 0;
    }
    if (o->fabric.empty()) throw CLI::RequiredError("FABRIC");
    if (o->output.empty()) throw CLI::RequiredError("--output");
    if (o->quiet) set_quiet(true);
    const compress::CompressRequest compression = compress_request(*o);
    const uint64_t max_memory = max_memory_option(o->max_memory, 1.0);
    take_warnings();
    // Check the report path before the bake, so that a typo does not cost a whole bake.
    formats::OutputOptions report_output;
    report_output.require_asset_to_replace = false;
    if (!o->report.empty()) formats::check_output_path(o->report, report_output);
    if (!o->depfile.empty()) formats::check_output_path(o->depfile, report_output);
    // Before any map is decoded or generated: a bake that cannot fit is refused in milliseconds
    // instead of failing (or being killed) after minutes.
    const std::optional<stages::MemoryEstimate> estimate = stages::check_fabric_memory(
        o->fabric, compression, o->stages, o->threads, max_memory, o->resolution);

    pipeline::BakeRequest request;
    request.fabric_path = o->fabric;
    request.output_path = o->output;
    request.force = o->force;
    request.stages = o->stages;
    request.run.threads = o->threads;
    request.run.show_progress = !o->quiet && pipeline::ProgressBar::stderr_is_terminal();
    request.run.record_timings = o->record_timings;
    if (!compression.given().empty())
      request.seeds.put(stages::kCompressSettingsArtifact, compression);
    if (o->resolution) request.seeds.put(stages::kFabricResolutionArtifact, *o->resolution);
    std::optional<reports::ScenePlanSeeds> planned;
    if (!o->scene.empty()) {
      if (o->no_compress || o->keep_raw || !o->stages.empty())
        throw Error(ExitCode::Usage,
                    "--scene bakes the compressed form of every stage: it cannot be combined "
                    "with --no-compress, --keep-raw or --stages");
      if (o->resolution)
        throw Error(ExitCode::Usage,
                    "--scene plans the fabric at its own resolution: it cannot be combined with "
                    "--resolution (set [bake] resolution in the fabric instead)");
      planned = reports::seed_scene_plan(o->scene, o->fabric, &request);
      for (const auto& what : planned->left_out)
        info("scene plan: left out " + what);
    }
    std::unique_ptr<cache::DiskCache> stage_cache;
    const std::string cache_dir = o->no_cache ? "" : cache::cache_dir_from(o->cache);
    // Timings would make entries differ; a scene plan changes what the stages compute without
    // being part of their cache key, so a planned bake does not use the stage cache.
    if (!cache_dir.empty() && !o->record_timings && !planned) {
      cache::CacheOptions cache_options;
      cache_options.dir = cache_dir;
      if (!o->cache_max_size.empty())
        cache_options.max_bytes = cache::parse_size(o->cache_max_size, "--cache-max-size");
      stage_cache = std::make_unique<cache::DiskCache>(cache_options, stages::artifact_codecs());
      request.run.cache = stage_cache.get();
    }
    // The asset is renamed into place last, after the report, the depfile and stdout succeeded:
    // a command that fails leaves no asset (and the previous one intact).
    request.defer_commit = true;
    const pipeline::BakeResult result = pipeline::bake(request, stages::bake_stages());

    nlohmann::json report = pipeline::bake_report_json(request, result);
    if (stage_cache) {
      const auto& c = stage_cache->counts();
      report["cache"] = {{"dir", cache_dir},
                         {"enabled", stage_cache->enabled()},
                         {"hits", c.hits},
                         {"stored", c.misses},
                         {"corrupt", c.corrupt},
                         {"unstored", c.unstored},
                         {"keys", stage_cache->keys()}};
    }
    nlohmann::json inputs = nlohmann::json::array();  // every file read (batch up-to-date checks)
    for (const auto& input : result.run.artifacts.get<Fabric>("fabric").inputs)
      inputs.push_back({{"role", input.role}, {"path", input.path}, {"xxh64", input.xxh64}});
    if (planned) {
      inputs.push_back({{"role", "scene"}, {"path", o->scene}, {"xxh64", planned->scene_hash}});
      report["scene_plan"] = planned->metadata;
    }
    report["inputs"] = inputs;
    report["memory_estimate"] =
        estimate ? stages::memory_estimate_json(*estimate) : nlohmann::json(nullptr);
    report["memory_estimate"]["max_memory_bytes"] = max_memory;
    report["warnings"] = take_warnings();
    std::string depfile;  // its text first: a path no depfile can hold fails before any write
    if (!o->depfile.empty()) {
      std::vector<std::string> deps;
      for (const auto& input : result.run.artifacts.get<Fabric>("fabric").inputs)
        deps.push_back(input.path);
      if (planned) deps.push_back(o->scene);
      if (const std::string exe = current_executable(); !exe.empty()) deps.push_back(exe);
      depfile = depfile_text(o->depfile_target.empty() ? o->output : o->depfile_target, deps);
    }
    if (o->json) {
      print_json(report);
      require_stdout_written();
    }
    if (!o->report.empty()) {
      const std::string text =
          report.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
      formats::write_file_atomically(
          o->report, [&](formats::Sink& sink) { sink.write(text.data(), text.size()); },
          report_output);
    }
    if (!o->depfile.empty()) formats::write_text_atomically(o->depfile, depfile);
    if (result.asset.pending) result.asset.pending->commit();
    // An unchanged asset is not rewritten, so no TempFile cleaned up after a killed earlier bake.
    if (result.asset.unchanged) formats::remove_stale_temp_files(result.asset.path);
    if (result.asset.unchanged)
      info(result.asset.path +
           " is up to date: the bake gave the same bytes, so the file and its "
           "mtime were left untouched");
    else
      info("wrote " + result.asset.path + " (" + std::to_string(result.asset.size_bytes) +
           " bytes, " + std::to_string(result.asset.sections.size()) + " sections) in " +
           std::to_string(result.run.wall_seconds) + " s");
    return 0;
  };
}

const bool bake_registered = register_command(
    {"bake", "Bake a fabric description into an asset (stages, threads, report)", setup_bake});

}  // namespace
}  // namespace clothbake::cli

// `clothbake report plan` (report_plan.hpp).
#include "bake/reports/report_plan.hpp"

#include <fmt/printf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "bake/inputs/scene_load.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/reports/render_error.hpp"
#include "bake/reports/scene_plan.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "formats/writer/atomic_file.hpp"
#include "model/splitmix64.hpp"
#include "render/image_output.hpp"
#include "render/renderer.hpp"
#include "render/sample_limit.hpp"

namespace clothbake::reports {
namespace {

namespace fs = std::filesystem;

struct FabricRow {
  std::string fabric, stem;
  std::vector<int> objects;
  std::string full_asset, planned_asset;
  uint64_t full_bytes = 0, planned_bytes = 0;
  double full_bake_seconds = 0, planned_bake_seconds = 0;
  double planned_vs_full = 0, planned_vs_full_error = 0, same_seed = 0;
  double full_vs_reference = 0, planned_vs_reference = 0;
  uint64_t pixels = 0;
  ScenePlanSeeds seeds;
  bool pass = true;
};

pipeline::BakeResult bake_one(const std::string& fabric, const std::string& output,
                              const inputs::LoadedScene& scene, const std::string& scene_path,
                              ScenePlanSeeds* seeds) {
  pipeline::BakeRequest request;
  request.fabric_path = fabric;
  request.output_path = output;
  if (seeds) *seeds = seed_scene_plan(scene, scene_path, fabric, &request);
  return pipeline::bake(request, stages::bake_stages());
}

}  // namespace

ReportOutput plan_report(const PlanReportOptions& o) {
  if (o.spp == 0) throw Error(ExitCode::Usage, "--spp must be at least 1");
  inputs::LoadedScene loaded = inputs::load_scene(o.scene);
  if (o.width > 0) {
    loaded.scene.camera.width = o.width;
    loaded.scene.camera.height = o.height;
  }
  render::check_render_samples(loaded.scene.camera.width, loaded.scene.camera.height, o.spp,
                               "--spp");
  render::check_render_samples(loaded.scene.camera.width, loaded.scene.camera.height,
                               o.reference_spp, "--reference-spp");
  const fs::path out(o.output);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw_input_error(o.output + ": exists and is not a directory");
  fs::create_directories(out / "assets", ec);
  if (ec) throw_input_error(o.output + ": cannot create the folder (" + ec.message() + ")");

  // One row per fabric file (objects sharing a fabric share its assets).
  std::vector<FabricRow> rows;
  for (std::size_t k = 0; k < loaded.fabrics.size(); ++k) {
    if (loaded.fabrics[k].empty()) continue;
    auto it = std::find_if(rows.begin(), rows.end(), [&](const FabricRow& r) {
      return fs::weakly_canonical(r.fabric, ec) == fs::weakly_canonical(loaded.fabrics[k], ec);
    });
    if (it == rows.end()) {
      FabricRow row;
      row.fabric = loaded.fabrics[k];
      // Appended in steps: GCC 12 warns (-Wrestrict, a false positive) on the one-expression form.
      row.stem = fs::path(row.fabric).stem().string();
      if (!rows.empty()) row.stem.append("-").append(std::to_string(rows.size()));
      rows.push_back(row);
      it = rows.end() - 1;
    }
    it->objects.push_back(int(k));
  }
  if (rows.empty())
    throw_input_error(o.scene + ": no object names a fabric (`fabric = ...`): nothing to plan");

  for (FabricRow& row : rows) {
    row.full_asset = (out / "assets" / (row.stem + "-full.cbk")).string();
    row.planned_asset = (out / "assets" / (row.stem + "-planned.cbk")).string();
    const pipeline::BakeResult full =
        bake_one(row.fabric, row.full_asset, loaded, o.scene, nullptr);
    const pipeline::BakeResult planned =
        bake_one(row.fabric, row.planned_asset, loaded, o.scene, &row.seeds);
    row.full_bytes = full.asset.size_bytes;
    row.planned_bytes = planned.asset.size_bytes;
    row.full_bake_seconds = full.run.wall_seconds;
    row.planned_bake_seconds = planned.run.wall_seconds;
  }

  // The renders: full assets, planned assets (same method, spp, seed), and the reference.
  auto scene_with = [&](bool planned) {
    render::Scene scene = loaded.scene;
    for (const FabricRow& row : rows)
      for (int k : row.objects)
        scene.objects[std::size_t(k)].asset = planned ? row.planned_asset : row.full_asset;
    return scene;
  };
  const render::Scene full_scene = scene_with(false), planned_scene = scene_with(true);
  bool environment = false;
  for (const render::Light& l : loaded.scene.lights)
    environment |= l.type == render::LightType::Environment;
  render::RenderOptions ro;
  ro.spp = o.spp;
  ro.seed = o.seed;
  // Every pixel from its centre, the full assets' too: the planned ones hold what the centres
  // query (edge pixels are not jittered over them), and the two renders must be alike.
  ro.jitter_edges = false;
  const render::Renderer full_renderer(full_scene, ro);
  const render::RenderResult full_image = full_renderer.render();
  const render::RenderResult planned_image = render::Renderer(planned_scene, ro).render();
  // The second, independent pair of the unbiased comparison (relmse_of_means).
  render::RenderOptions ro2 = ro;
  // A full 64-bit seed: the renderer's per-pixel seeds XOR the pixel index into the seed, so a
  // seed that differs from the first in low bits only would give some pixels another pixel's
  // random numbers of the first pair.
  uint64_t seed_state = o.seed;
  ro2.seed = model::splitmix64_next(seed_state);
  const render::RenderResult full_image2 = render::Renderer(full_scene, ro2).render();
  const render::RenderResult planned_image2 = render::Renderer(planned_scene, ro2).render();
  render::RenderOptions ref_options;
  ref_options.method = eval::Method::Reference;
  ref_options.spp = environment ? o.reference_spp : 1;
  ref_options.seed = o.seed + 1000003;
  ref_options.jitter_edges = false;
  const render::RenderResult reference = render::Renderer(full_scene, ref_options).render();

  // Per fabric: the pixels whose primary hit is one of its objects.
  const int w = full_scene.camera.width, h = full_scene.camera.height;
  std::vector<int> hit(std::size_t(w) * h, -1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      hit[std::size_t(y) * w + x] = full_renderer.pixel_footprint(x, y).object;
  const double budget = loaded.scene.max_error;
  bool all_pass = true;
  nlohmann::json fabrics = nlohmann::json::array();
  for (FabricRow& row : rows) {
    std::vector<uint8_t> mask(hit.size(), 0);
    for (std::size_t p = 0; p < hit.size(); ++p)
      if (std::find(row.objects.begin(), row.objects.end(), hit[p]) != row.objects.end())
        mask[p] = 1, ++row.pixels;
    const MeanAndError of_means =
        relmse_of_means(planned_image, full_image, planned_image2, full_image2, reference, mask);
    row.planned_vs_full = of_means.mean;
    row.planned_vs_full_error = of_means.std_error;
    row.same_seed = relmse_between(planned_image, full_image, reference, mask);
    row.full_vs_reference = masked_relmse(full_image, reference, mask);
    row.planned_vs_reference = masked_relmse(planned_image, reference, mask);
    row.pass = row.planned_vs_full <= budget;
    if (row.planned_vs_full_error > budget / 4)
      warn("report plan: " + row.fabric + ": the comparison's standard error " +
           std::to_string(row.planned_vs_full_error) + " is above a quarter of the budget " +
           std::to_string(budget) +
           ": it cannot resolve the budget; raise --spp or the image size");
    all_pass = all_pass && row.pass;
    fabrics.push_back(
        {{"fabric", row.fabric},
         {"objects", row.objects},
         {"pixels", row.pixels},
         {"full_asset", row.full_asset},
         {"planned_asset", row.planned_asset},
         {"full_bytes", row.full_bytes},
         {"planned_bytes", row.planned_bytes},
         {"size_ratio", row.planned_bytes ? double(row.full_bytes) / double(row.planned_bytes) : 0},
         {"full_bake_seconds", row.full_bake_seconds},
         {"planned_bake_seconds", row.planned_bake_seconds},
         {"bake_speedup",
          row.planned_bake_seconds > 0 ? row.full_bake_seconds / row.planned_bake_seconds : 0},
         {"relmse",
          {{"planned_vs_full", row.planned_vs_full},
           {"planned_vs_full_std_error", row.planned_vs_full_error},
           {"planned_vs_full_same_seed", row.same_seed},
           {"full_vs_reference", row.full_vs_reference},
           {"planned_vs_reference", row.planned_vs_reference}}},
         {"relative_rms_planned_vs_full", std::sqrt(std::max(row.planned_vs_full, 0.0))},
         {"budget", budget},
         {"pass", row.pass},
         {"left_out", row.seeds.left_out}});
  }

  // Side by side: full | planned | where the expected picture changes: the terms of
  // relmse_of_means, (P1 - F1)(P2 - F2) / (R^2 + eps^2) averaged over the channels, pooled in
  // blocks of B x B pixels (B = max(2, min(w, h) / 16)), shown as sqrt(max(0, mean - 2 standard
  // errors) / budget). A pixel's term is mostly noise that the two pairs do not share, of either
  // sign; the block's lower bound is zero where only noise is, and at the budget (yellow) where the
  // block's pixels alone would reach it.
  const double floor2_all = relmse_floor(reference, {});
  const int block = std::max(2, std::min(w, h) / 16);
  const int bw = (w + block - 1) / block, bh = (h + block - 1) / block;
  std::vector<double> block_sum(std::size_t(bw) * bh, 0.0), block_sum2(block_sum.size(), 0.0);
  std::vector<int> block_count(block_sum.size(), 0);
  Image side(3 * w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t p = std::size_t(y) * w + x;
      render::preview_value(&full_image.rgb[3 * p], loaded.scene.preview,
                            &side.pixels[(std::size_t(y) * 3 * w + x) * 3]);
      render::preview_value(&planned_image.rgb[3 * p], loaded.scene.preview,
                            &side.pixels[(std::size_t(y) * 3 * w + w + x) * 3]);
      if (hit[p] < 0) continue;  // no object: stays black
      const double term = relmse_of_means_term(planned_image, full_image, planned_image2,
                                               full_image2, reference, p, floor2_all);
      const std::size_t b = std::size_t(y / block) * bw + std::size_t(x / block);
      block_sum[b] += term;
      block_sum2[b] += term * term;
      ++block_count[b];
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t b = std::size_t(y / block) * bw + std::size_t(x / block);
      const int count = block_count[b];
      if (hit[std::size_t(y) * w + x] < 0 || count < 2) continue;
      const double mean = block_sum[b] / count;
      const double var = std::max(0.0, (block_sum2[b] - count * mean * mean) / (count - 1));
      const double lower = mean - 2 * std::sqrt(var / count);
      const double e = std::min(1.0, std::sqrt(std::max(lower, 0.0) / budget));
      // False colour: black (equal) through red to yellow (at or over the budget).
      const float r = float(std::min(1.0, 2 * e)), g = float(std::max(0.0, 2 * e - 1));
      const std::size_t q = (std::size_t(y) * 3 * w + 2 * w + x) * 3;
      side.pixels[q] = r, side.pixels[q + 1] = g, side.pixels[q + 2] = 0;
    }
  render::write_image_atomically(out / "side-by-side.png", side, PixelType::UInt8);
  render::write_render_images((out / "full.exr").string(), full_image, loaded.scene.preview);
  render::write_render_images((out / "planned.exr").string(), planned_image, loaded.scene.preview);
  render::write_render_images((out / "reference.exr").string(), reference, loaded.scene.preview);

  const nlohmann::json doc = {{"scene", o.scene},
                              {"budget", budget},
                              {"spp", o.spp},
                              {"seed", o.seed},
                              {"resolution", {w, h}},
                              {"pass", all_pass},
                              {"criterion",
                               "relmse planned_vs_full (of the expected renders, two "
                               "independent same-seed pairs) <= budget"},
                              {"out_of_plan",
                               {{"estimates", planned_image.stats.out_of_plan},
                                {"brute_fallback", planned_image.stats.fallback_brute},
                                {"zero", planned_image.stats.fallback_zero}}},
                              {"fabrics", fabrics}};
  formats::write_text_atomically(out / "plan.json", doc.dump(2) + "\n");
  ReportOutput result;
  std::string& text = result.summary;
  {
    text += fmt::sprintf("plan report for %s (budget %.3g %%, %dx%d, %u spp)\n",
                         terminal_safe(o.scene).c_str(), 100 * budget, w, h, unsigned(o.spp));
    for (const FabricRow& row : rows) {
      text += fmt::sprintf(
          "%s: %llu -> %llu bytes (%.1fx smaller), bake %.2f -> %.2f s (%.2fx)\n",
          terminal_safe(row.fabric).c_str(), static_cast<unsigned long long>(row.full_bytes),
          static_cast<unsigned long long>(row.planned_bytes),
          double(row.full_bytes) / double(std::max<uint64_t>(row.planned_bytes, 1)),
          row.full_bake_seconds, row.planned_bake_seconds,
          row.full_bake_seconds / std::max(row.planned_bake_seconds, 1e-9));
      text += fmt::sprintf(
          "  relMSE planned vs full %.3g +- %.2g (budget %.3g: %s; relative RMS %.3g %%; one "
          "same-seed pair %.3g); vs reference: full %.3g, planned %.3g\n",
          row.planned_vs_full, row.planned_vs_full_error, budget, row.pass ? "within" : "OVER",
          100 * std::sqrt(std::max(row.planned_vs_full, 0.0)), row.same_seed, row.full_vs_reference,
          row.planned_vs_reference);
      for (const auto& what : row.seeds.left_out)
        text += fmt::sprintf("  left out: %s\n", terminal_safe(what).c_str());
    }
    text += fmt::sprintf("out-of-plan estimates %llu (brute-force fallback %llu, zero %llu)\n",
                         static_cast<unsigned long long>(planned_image.stats.out_of_plan),
                         static_cast<unsigned long long>(planned_image.stats.fallback_brute),
                         static_cast<unsigned long long>(planned_image.stats.fallback_zero));
    text += fmt::sprintf(
        "  %s/{plan.json,side-by-side.png,full.exr,planned.exr,reference.exr,assets/}\n",
        terminal_safe(o.output).c_str());
  }
  if (!all_pass)
    result.failure = "report plan: a planned render is over the scene's budget (see " +
                     (out / "plan.json").string() + ")";
  result.doc = std::move(doc);
  return result;
}

}  // namespace clothbake::reports

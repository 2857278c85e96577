// clothbake report error-time SCENE.toml -o DIR (report_error_time.hpp; docs/rendering.md,
// "Error against run time").
#include "bake/reports/report_error_time.hpp"

#include <fmt/format.h>
#include <fmt/printf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/progress.hpp"
#include "bake/reports/render_error.hpp"
#include "bake/reports/scene_bake.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "common/version.hpp"
#include "formats/writer/atomic_file.hpp"
#include "render/heightfield_reference.hpp"
#include "render/image_output.hpp"
#include "render/renderer.hpp"
#include "render/sample_limit.hpp"

namespace clothbake::reports {
namespace {

namespace fs = std::filesystem;

struct Row {
  std::string method;
  uint32_t spp = 0;
  double seconds = 0, rmse = 0, relmse = 0, bias = 0;
  // Against the path-traced truth (NaN without it), its own noise removed: over every pixel and
  // over the compared (interior) pixels.
  double relmse_truth = NAN, relmse_truth_interior = NAN;
  render::RenderResult image;
};

// relMSE (render_error.hpp) and the absolute RMSE over the pixels of `mask`.
void errors(const render::RenderResult& a, const render::RenderResult& ref,
            const std::vector<uint8_t>& mask, double* relmse, double* rmse) {
  double abs2 = 0;
  std::size_t count = 0;
  for (std::size_t k = 0; k < ref.rgb.size(); ++k) {
    if (!mask[k / 3]) continue;
    const double d = double(a.rgb[k]) - ref.rgb[k];
    abs2 += d * d;
    ++count;
  }
  *relmse = masked_relmse(a, ref, mask);
  *rmse = count == 0 ? 0 : std::sqrt(abs2 / double(count));
}

// The relative bias of a method from two independent renders a, b at one spp: with weights
// w = r^2 + eps^2 as relMSE uses, E[(a - r)^2 / w] = bias^2 + var and E[(a - b)^2 / w] = 2 var, so
// bias^2 = relMSE(a) - mean((a - b)^2 / w) / 2 (clamped at 0; the estimate has the noise of the
// two renders, so it is meaningful where bias^2 is not small against var / spp).
double bias_estimate(const render::RenderResult& a, const render::RenderResult& b,
                     const render::RenderResult& ref, const std::vector<uint8_t>& mask) {
  return std::sqrt(
      std::max(0.0, masked_relmse(a, ref, mask) - 0.5 * relmse_between(a, b, ref, mask)));
}

// Value of y at x on the log-log polyline through (xs, ys) sorted by x; NaN outside.
double loglog_at(const std::vector<std::pair<double, double>>& pts, double x, bool by_y) {
  for (std::size_t k = 1; k < pts.size(); ++k) {
    double a0 = pts[k - 1].first, a1 = pts[k].first, b0 = pts[k - 1].second, b1 = pts[k].second;
    if (by_y) std::swap(a0, b0), std::swap(a1, b1);
    if ((x - a0) * (x - a1) <= 0 && a0 != a1 && a0 > 0 && a1 > 0 && b0 > 0 && b1 > 0) {
      const double u = (std::log(x) - std::log(a0)) / (std::log(a1) - std::log(a0));
      return std::exp(std::log(b0) + u * (std::log(b1) - std::log(b0)));
    }
  }
  return NAN;
}

// A render the report cached (the reference, a half of the truth), or an empty result when there
// is none. A cache entry that is not what this report renders (not a regular file, unreadable,
// another size, not three finite channels >= 0) is removed with a warning naming `what`.
render::RenderResult load_cached_render(const fs::path& cached, int width, int height,
                                        const char* what) {
  render::RenderResult result;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(cached, ec))) return result;
  std::string problem;
  try {
    ImageReadLimits limits;
    limits.max_side = width > height ? width : height;
    inputs::require_regular_file(cached.string());
    const Image img = read_image(cached.string(), limits);
    if (img.width != width || img.height != height || img.channels != 3)
      problem = fmt::format("{}x{} with {} channels, not {}x{} RGB", img.width, img.height,
                            img.channels, width, height);
    for (std::size_t i = 0; problem.empty() && i < img.pixels.size(); ++i)
      if (!(img.pixels[i] >= 0.f) || !std::isfinite(img.pixels[i]))
        problem = fmt::format("pixel ({}, {}) holds {}", i / 3 % img.width, i / 3 / img.width,
                              img.pixels[i]);
    if (problem.empty()) {
      result.width = img.width;
      result.height = img.height;
      result.rgb = img.pixels;
    }
  } catch (const Error& e) {
    problem = e.what();
  }
  if (!problem.empty()) {
    warn(fmt::format("cached {} {} is unusable ({}): removed, rendering it again", what,
                     cached.string(), problem));
    fs::remove(cached, ec);
  }
  return result;
}

// The picture of one render as `clothbake render` previews it (the scene's exposure, tone map).
void write_png(const fs::path& path, const render::RenderResult& r,
               const render::Preview& preview) {
  render::write_image_atomically(path, render::preview_image(r, preview), PixelType::UInt8);
}

// A grey relative-error map, |x - r| / r of the channel mean, scaled to [0, 1] by `scale`.
void write_error_png(const fs::path& path, const render::RenderResult& a,
                     const render::RenderResult& ref, double scale) {
  Image img(ref.width, ref.height, 1);
  for (int k = 0; k < ref.width * ref.height; ++k) {
    double x = 0, r = 0;
    for (int c = 0; c < 3; ++c)
      x += a.rgb[3 * k + c], r += ref.rgb[3 * k + c];
    const double e = r > 1e-6 ? std::abs(x - r) / r : 0.0;
    img.pixels[std::size_t(k)] = float(std::min(1.0, e / scale));
  }
  render::write_image_atomically(path, img, PixelType::UInt8);
}

}  // namespace

ReportOutput error_time_report(const ErrorTimeOptions& o) {
  // A rendered method: the evaluator's, over the pixel footprint, or brute force path-traced.
  struct Method {
    std::string name;
    eval::Method method;
    bool path_traced;
  };
  std::vector<Method> methods;
  for (const std::string& name : o.methods) {
    eval::Method m;
    if (name == "brute-path")
      methods.push_back({name, eval::Method::Brute, true});
    else if (eval::parse_method(name.c_str(), &m) && m != eval::Method::Reference)
      methods.push_back({name, m, false});
    else
      throw Error(ExitCode::Usage, "--methods: unknown method '" + name +
                                       "' (multiscale, multiscale-paper, brute, brute-path)");
  }
  if (methods.empty()) throw Error(ExitCode::Usage, "--methods: no method given");
  if (o.spp.empty()) throw Error(ExitCode::Usage, "--spp: no spp given");
  for (uint32_t s : o.spp)
    if (s == 0) throw Error(ExitCode::Usage, "--spp: every spp must be at least 1");
  if (o.truth_spp % 2 != 0)
    throw Error(ExitCode::Usage,
                "--truth-spp: 0 (no path-traced truth) or an even number (two independent halves), "
                "not " +
                    std::to_string(o.truth_spp));
  const fs::path out(o.output);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw_input_error(o.output + ": exists and is not a directory");
  // Refused now if it could not be made later: the folder itself is made only when the renders
  // are done, so that an interrupted report leaves nothing (not even an empty folder).
  formats::check_creatable_folder(out, o.output);

  // Everything that can refuse the scene comes before anything is written.
  inputs::LoadedScene loaded = inputs::load_scene(o.scene);
  if (o.width > 0 && o.height > 0) {
    loaded.scene.camera.width = o.width;
    loaded.scene.camera.height = o.height;
  }
  const render::Scene& scene = loaded.scene;
  bool environment = false;
  for (const render::Light& l : scene.lights)
    environment |= l.type == render::LightType::Environment;
  // The sample bound before anything is baked (minutes for a scene's fabrics).
  for (uint32_t spp : o.spp)
    render::check_render_samples(scene.camera.width, scene.camera.height, spp, "--spp");
  render::check_render_samples(scene.camera.width, scene.camera.height,
                               environment ? o.reference_spp : 1, "--reference-spp");
  if (o.truth_spp > 0)
    render::check_render_samples(scene.camera.width, scene.camera.height, o.truth_spp / 2,
                                 "--truth-spp");
  bake_scene_fabrics(loaded, o.cache, o.quiet);
  std::size_t near_field_object = scene.objects.size();
  if (o.near_field) {
    for (std::size_t k = 0; k < scene.objects.size(); ++k)
      if (scene.objects[k].shape == render::ShapeType::Plane && !scene.objects[k].asset.empty()) {
        near_field_object = k;
        break;
      }
    if (near_field_object == scene.objects.size())
      throw_input_error(o.scene + ": --near-field needs a plane with a fabric");
  }
  // The reference: exact footprints; environment lights need many light samples. Cached by the
  // content of everything it depends on: the tool's version, the scene file, the image size, the
  // reference's spp and seed, every asset and every environment map (its pixels and scale, so that
  // an edited map is not answered with a stale reference).
  render::RenderOptions ref_options;
  ref_options.method = eval::Method::Reference;
  ref_options.spp = environment ? o.reference_spp : 1;
  ref_options.seed = o.seed + 1000003;
  ref_options.jitter_edges = false;  // the footprint integral at each pixel's centre
  // The truth is keyed the same way, its spp and seeds in place of the reference's.
  const std::string key_head =
      fmt::format("{} {} {}x{}", CLOTHBAKE_VERSION_STRING, inputs::hash_file(o.scene),
                  scene.camera.width, scene.camera.height);
  std::string key_tail;
  std::map<std::string, std::string> asset_hashes;  // each file read once, however many objects
  for (const render::Object& obj : scene.objects)
    if (!obj.asset.empty()) {
      std::string& hash = asset_hashes[obj.asset];
      if (hash.empty()) hash = inputs::hash_file(obj.asset);
      key_tail += " " + hash;
    }
  for (const render::Light& l : scene.lights)
    if (l.type == render::LightType::Environment) {
      const render::EnvironmentMap& map = l.environment;
      key_tail += fmt::format(" env {}x{} scale {} ", map.width, map.height, map.scale) +
                  inputs::xxh64_hex(std::string_view(reinterpret_cast<const char*>(map.rgb.data()),
                                                     map.rgb.size() * sizeof(float)));
    }
  const fs::path cache_dir = scene_cache_dir(o.cache);
  fs::create_directories(cache_dir, ec);
  const std::string key =
      fmt::format("{} spp {} seed {}", key_head, ref_options.spp, ref_options.seed) + key_tail;
  const fs::path cached = cache_dir / ("reference-" + inputs::xxh64_hex(key) + ".exr");
  // The truth's two halves, brute-path at truth_spp / 2 each with their own seeds.
  const uint64_t truth_seeds[2] = {o.seed + 2000003, o.seed + 3000017};
  const std::string truth_key = fmt::format("{} truth spp {} seeds {} {}", key_head, o.truth_spp,
                                            truth_seeds[0], truth_seeds[1]) +
                                key_tail;
  const fs::path truth_cached[2] = {
      cache_dir / ("truth-" + inputs::xxh64_hex(truth_key) + "-a.exr"),
      cache_dir / ("truth-" + inputs::xxh64_hex(truth_key) + "-b.exr")};
  // One renderer for every render of the report: its evaluators keep what they build on first use
  // (the parallax planes of the views met, per-bin tables), as a renderer keeps its assets between
  // frames, so that the timed renders measure shading, not the asset's one-time preparation.
  const render::Renderer renderer(scene, ref_options);
  // Errors are compared on the pixels off silhouettes and shadow edges: there the footprint
  // methods (and the reference) shade the centre's hit with its shadow rays while path tracing
  // averages over the pixel's area, so they converge to different values that no sample count
  // removes.
  const std::vector<uint8_t> compared = renderer.interior_pixels();
  const std::size_t pixels_compared = std::size_t(std::count(compared.begin(), compared.end(), 1));
  // --raw-tables: the same scene over assets with both table forms, one renderer per form (an
  // `asset =` without raw tables is refused here, exit 2 naming the object). After the main
  // renderer has opened its assets and the reference key has read them: this bake may prune the
  // cache (its bound) and with it the assets just baked.
  inputs::LoadedScene raw_loaded;
  std::unique_ptr<render::Renderer> with_raw, with_compressed;
  if (o.raw_tables) {
    raw_loaded = inputs::load_scene(o.scene);
    bake_scene_fabrics(raw_loaded, o.cache, true, /*keep_raw_tables=*/true);
    raw_loaded.scene.camera = scene.camera;
    render::RenderOptions form;
    form.tables = eval::TableChoice::Raw;
    with_raw = std::make_unique<render::Renderer>(raw_loaded.scene, form);
    form.tables = eval::TableChoice::Compressed;
    with_compressed = std::make_unique<render::Renderer>(raw_loaded.scene, form);
  }
  render::RenderResult reference =
      load_cached_render(cached, scene.camera.width, scene.camera.height, "reference");
  double reference_seconds = 0;
  // On a terminal (not with --json) every render shows a bar, and the reference says what it
  // costs: it is the report's longest render by far.
  pipeline::ProgressBar bar(!o.quiet && pipeline::ProgressBar::stderr_is_terminal());
  auto progress = [&bar](double f) { bar.update(f); };
  if (reference.rgb.empty()) {
    if (bar.enabled())
      std::fprintf(stderr,
                   "rendering the reference once (then cached): %dx%d pixels, every footprint "
                   "summed exactly; its time grows with the pixels and their footprints "
                   "(--image-size W,H renders fewer)\n",
                   scene.camera.width, scene.camera.height);
    bar.begin(fmt::format("reference {}x{}", scene.camera.width, scene.camera.height));
    reference = renderer.render(ref_options, progress);
    bar.finish();
    reference_seconds = reference.stats.seconds;
    render::write_render_images(cached.string(), reference, scene.preview);
  }
  // The path-traced truth: what brute-path converges to (each sample its own camera ray through a
  // uniform point of the pixel), as two independent halves whose difference measures the noise
  // left in their average, which relmse_against_noisy removes from every error against it.
  render::RenderResult truth_half[2], truth;
  double truth_seconds = 0;
  const std::vector<uint8_t> every_pixel(compared.size(), 1);
  if (o.truth_spp > 0) {
    for (int h = 0; h < 2; ++h) {
      truth_half[h] = load_cached_render(truth_cached[h], scene.camera.width, scene.camera.height,
                                         "path-traced truth");
      if (!truth_half[h].rgb.empty()) continue;
      render::RenderOptions ro;
      ro.method = eval::Method::Brute;
      ro.path_traced = true;
      ro.spp = o.truth_spp / 2;
      ro.seed = truth_seeds[h];
      bar.begin(fmt::format("path-traced truth {}/2, {} spp", h + 1, ro.spp));
      truth_half[h] = renderer.render(ro, progress);
      bar.finish();
      truth_seconds += truth_half[h].stats.seconds;
      render::write_render_images(truth_cached[h].string(), truth_half[h], scene.preview);
    }
    truth = truth_half[0];
    for (std::size_t k = 0; k < truth.rgb.size(); ++k)
      truth.rgb[k] = 0.5f * (truth_half[0].rgb[k] + truth_half[1].rgb[k]);
  }
  // A render's relMSE against the truth, over `mask`, its noise removed.
  auto against_truth = [&](const render::RenderResult& image, const std::vector<uint8_t>& mask) {
    return relmse_against_noisy(image, truth_half[0], truth_half[1], truth, mask);
  };
  // Each method's first render at 1 spp, untimed in the rows: it builds what the method reads on
  // first use (its time is reported as `warmup`).
  nlohmann::json warmup = nlohmann::json::object();
  for (const Method& m : methods) {
    render::RenderOptions ro;
    ro.method = m.method;
    ro.path_traced = m.path_traced;
    ro.spp = 1;
    ro.seed = o.seed + 31337;
    bar.begin(fmt::format("warm-up {}", m.name));
    warmup[m.name] = renderer.render(ro, progress).stats.seconds;
  }
  const std::size_t row_count = methods.size() * o.spp.size();
  std::vector<Row> rows;
  for (const Method& m : methods)
    for (uint32_t spp : o.spp) {
      render::RenderOptions ro;
      ro.method = m.method;
      ro.path_traced = m.path_traced;
      ro.spp = spp;
      ro.seed = o.seed;
      Row row;
      row.method = m.name;
      row.spp = spp;
      bar.begin(fmt::format("[{}/{}] {} {} spp", rows.size() + 1, row_count, m.name, spp));
      row.image = renderer.render(ro, progress);
      row.seconds = row.image.stats.seconds;
      errors(row.image, reference, compared, &row.relmse, &row.rmse);
      if (o.truth_spp > 0) {
        row.relmse_truth = against_truth(row.image, every_pixel);
        row.relmse_truth_interior = against_truth(row.image, compared);
      }
      rows.push_back(std::move(row));
    }
  // Each method's bias: its largest-spp render against a second one with another seed.
  for (const Method& m : methods) {
    const Row* last = nullptr;
    for (const Row& r : rows)
      if (r.method == m.name && (!last || r.spp > last->spp)) last = &r;
    render::RenderOptions ro;
    ro.method = m.method;
    ro.path_traced = m.path_traced;
    ro.spp = last->spp;
    ro.seed = o.seed + 7777;
    bar.begin(fmt::format("bias {} {} spp", m.name, last->spp));
    const double bias =
        bias_estimate(last->image, renderer.render(ro, progress), reference, compared);
    for (Row& r : rows)
      if (r.method == m.name) r.bias = bias;
  }
  bar.finish();
  fs::create_directories(out / "images", ec);
  if (ec) throw_input_error(o.output + ": cannot create it (" + ec.message() + ")");
  // `error` picks the judge: the reference (relmse) or the path-traced truth (relmse_truth).
  auto curve = [&](const std::string& method, double Row::*error) {
    std::vector<std::pair<double, double>> pts;  // (seconds, error) by seconds
    for (const Row& r : rows)
      if (r.method == method) pts.push_back({r.seconds, r.*error});
    std::sort(pts.begin(), pts.end());
    return pts;
  };
  const Row* operating = nullptr;  // multiscale at 2 spp (or its nearest spp)
  for (const Row& r : rows)
    if (r.method == "multiscale" &&
        (!operating || std::abs(int(r.spp) - 2) < std::abs(int(operating->spp) - 2)))
      operating = &r;

  nlohmann::json summary = nlohmann::json::object();
  const auto brute = curve("brute", &Row::relmse);
  nlohmann::json grid = nlohmann::json::array();
  // A baseline's cost at a target error: interpolated inside its sweep (log-log on the error axis);
  // outside, a bound: its cheapest render when even that is more accurate (an upper bound of the
  // speedup), its costliest when even that is less accurate (a lower bound; or extrapolated,
  // below). `error` picks the judge, `spp` the cost: samples per pixel, else seconds.
  struct AtError {
    double cost;
    const char* bound;  // "none", "upper", "lower" (of the speedup) or "extrapolated"
  };
  auto baseline_at = [&](const std::string& baseline, double Row::*error, double target,
                         bool spp) -> AtError {
    std::vector<std::pair<double, double>> pts;  // (cost, error) by decreasing error
    for (const Row& r : rows)
      if (r.method == baseline) pts.push_back({spp ? double(r.spp) : r.seconds, r.*error});
    std::sort(pts.begin(), pts.end(),
              [](const auto& x, const auto& y) { return x.second > y.second; });
    const double c = loglog_at(pts, target, true);
    if (std::isfinite(c)) return {c, "none"};
    double worst = 0, cheapest = INFINITY, costliest = 0, error_at_costliest = 0;
    for (const auto& [cost, err] : pts) {
      worst = std::max(worst, err);
      cheapest = std::min(cheapest, cost);
      if (cost >= costliest) costliest = cost, error_at_costliest = err;
    }
    if (worst <= target) return {cheapest, "upper"};
    // brute-path judged by the truth is the truth's own estimator, unbiased, so its error falls as
    // 1 / spp and its cost grows as spp: beyond the sweep the cost of an error is extrapolated.
    if (baseline == "brute-path" && error == &Row::relmse_truth && target > 0 &&
        error_at_costliest > target)
      return {costliest * error_at_costliest / target, "extrapolated"};
    return {costliest, "lower"};
  };
  if (operating) {
    summary["operating_point"] = {{"method", "multiscale"},
                                  {"spp", operating->spp},
                                  {"seconds", operating->seconds},
                                  {"relmse", operating->relmse}};
    // Every other method at the operating spp against each brute-force baseline present: the
    // equal-error ratio in time and in samples per pixel (the paper's Table 1 columns), and the
    // error ratio at equal time; judged by the path-traced truth first (over every pixel), then
    // by the reference (over the compared pixels).
    summary["pairs"] = nlohmann::json::array();
    std::vector<std::pair<std::string, double Row::*>> judges;
    if (o.truth_spp > 0) judges.push_back({"truth", &Row::relmse_truth});
    judges.push_back({"reference", &Row::relmse});
    for (const auto& [judge, error] : judges)
      for (const std::string& baseline : {std::string("brute"), std::string("brute-path")}) {
        if (curve(baseline, error).empty()) continue;
        for (const Row& r : rows) {
          if (r.method == "brute" || r.method == "brute-path" || r.spp != operating->spp) continue;
          const AtError t = baseline_at(baseline, error, r.*error, false);
          const AtError n = baseline_at(baseline, error, r.*error, true);
          const double e = loglog_at(curve(baseline, error), r.seconds, false);
          summary["pairs"].push_back(
              {{"method", r.method},
               {"against", baseline},
               {"judge", judge},
               {"spp", r.spp},
               {"equal_error_speedup", t.cost / r.seconds},
               {"equal_error_speedup_bound", t.bound},
               {"equal_error_spp_ratio", n.cost / double(r.spp)},
               {"equal_error_spp_ratio_bound", n.bound},
               {"equal_time_error_ratio",
                std::isfinite(e) ? nlohmann::json(e / (r.*error)) : nlohmann::json(nullptr)}});
        }
      }
  }
  // Against brute force judged by the reference: the summary's headline and the picture grid.
  if (operating && !brute.empty()) {
    const AtError at = baseline_at("brute", &Row::relmse, operating->relmse, false);
    const double e_equal_time = loglog_at(brute, operating->seconds, false);
    summary["equal_error_speedup"] = at.cost / operating->seconds;
    // "none": interpolated; "lower": brute force never reached the error within the sweep (the
    // speedup is at least this); "upper": even its fastest render was more accurate (at most this).
    summary["equal_error_speedup_bound"] = at.bound;
    summary["brute_at_equal_error"] = {
        {"seconds", std::string(at.bound) == "none" ? nlohmann::json(at.cost) : nullptr}};
    summary["equal_time_error_ratio"] = std::isfinite(e_equal_time)
                                            ? nlohmann::json(e_equal_time / operating->relmse)
                                            : nlohmann::json(nullptr);
    // The picture grid: reference, the operating point, brute force nearest in time and nearest
    // in error (at or below the operating point's error, else the best brute render).
    const Row* equal_time = nullptr;
    const Row* equal_error = nullptr;
    for (const Row& r : rows) {
      if (r.method != "brute") continue;
      if (!equal_time || std::abs(std::log(r.seconds / operating->seconds)) <
                             std::abs(std::log(equal_time->seconds / operating->seconds)))
        equal_time = &r;
      if (r.relmse <= operating->relmse && (!equal_error || r.seconds < equal_error->seconds))
        equal_error = &r;
    }
    if (!equal_error)
      for (const Row& r : rows)
        if (r.method == "brute" && (!equal_error || r.relmse < equal_error->relmse))
          equal_error = &r;
    const double scale = std::max(0.05, 2 * std::sqrt(operating->relmse));
    if (o.truth_spp > 0) {
      write_png(out / "images" / "truth.png", truth, scene.preview);
      grid.push_back({{"label", fmt::format("path-traced truth {} spp", o.truth_spp)},
                      {"image", "images/truth.png"}});
    }
    write_png(out / "images" / "reference.png", reference, scene.preview);
    grid.push_back({{"label", "reference"}, {"image", "images/reference.png"}});
    auto panel = [&](const Row* r, const std::string& name, const std::string& label) {
      write_png(out / "images" / (name + ".png"), r->image, scene.preview);
      write_error_png(out / "images" / (name + "-error.png"), r->image, reference, scale);
      grid.push_back({{"label", fmt::format("{} {} spp ({:.2g} s, relMSE {:.2g})", label, r->spp,
                                            r->seconds, r->relmse)},
                      {"image", "images/" + name + ".png"},
                      {"error", "images/" + name + "-error.png"},
                      {"error_scale", scale}});
    };
    panel(operating, "multiscale", "multi-scale");
    panel(equal_time, "brute-equal-time", "brute, equal time:");
    panel(equal_error, "brute-equal-error", "brute, equal error:");
  }

  // What the compression changes: each multi-scale method at the sweep's largest spp, the same
  // seed, with the raw and with the compressed tables of the same assets.
  nlohmann::json tables = nullptr;
  if (o.raw_tables) {
    const uint32_t spp = *std::max_element(o.spp.begin(), o.spp.end());
    tables = {{"spp", spp}, {"methods", nlohmann::json::object()}};
    for (const Method& method : methods) {
      const eval::Method m = method.method;
      if (m == eval::Method::Brute) continue;  // reads no table
      render::RenderOptions ro;
      ro.method = m;
      ro.spp = spp;
      ro.seed = o.seed;
      ro.tables = eval::TableChoice::Raw;
      const render::RenderResult raw = with_raw->render(ro);
      ro.tables = eval::TableChoice::Compressed;
      const render::RenderResult compressed = with_compressed->render(ro);
      tables["methods"][eval::method_name(m)] = {
          {"relmse_compressed_vs_raw", masked_relmse(compressed, raw, compared)},
          {"relmse_raw", masked_relmse(raw, reference, compared)},
          {"relmse_compressed", masked_relmse(compressed, reference, compared)}};
    }
  }

  // Near field: the ray-traced relief against the model with and without parallax offsets.
  nlohmann::json near_field = nullptr;
  if (o.near_field) {
    const std::size_t object = near_field_object;
    const render::HeightfieldReference traced =
        render::render_heightfield_reference(scene, object, o.near_field_samples);
    render::RenderOptions flat = ref_options;
    flat.parallax = false;
    const render::RenderResult no_offsets = render::Renderer(scene, flat).render();
    write_png(out / "images" / "raytraced.png", traced.image, scene.preview);
    write_png(out / "images" / "no-offsets.png", no_offsets, scene.preview);
    near_field = {
        {"object", scene.objects[object].name},
        {"samples_per_pixel", o.near_field_samples * o.near_field_samples},
        {"raytraced_seconds", traced.image.stats.seconds},
        {"relmse_parallax_model", masked_relmse(reference, traced.image, traced.mask)},
        {"relmse_without_offsets", masked_relmse(no_offsets, traced.image, traced.mask)},
        {"images", {"images/raytraced.png", "images/reference.png", "images/no-offsets.png"}}};
    if (!fs::exists(out / "images" / "reference.png"))
      write_png(out / "images" / "reference.png", reference, scene.preview);
  }

  // CSV and JSON.
  std::string csv =
      "scene,method,spp,seconds,rmse,relmse,bias_estimate,relmse_truth,relmse_truth_interior\n";
  nlohmann::json jrows = nlohmann::json::array();
  auto or_null = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(); };
  auto or_empty = [](double x) { return std::isfinite(x) ? fmt::format("{:.6g}", x) : ""; };
  for (const Row& r : rows) {
    csv +=
        fmt::format("{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{},{}\n",
                    fs::path(o.scene).filename().string(), r.method, r.spp, r.seconds, r.rmse,
                    r.relmse, r.bias, or_empty(r.relmse_truth), or_empty(r.relmse_truth_interior));
    jrows.push_back({{"method", r.method},
                     {"spp", r.spp},
                     {"seconds", r.seconds},
                     {"rmse", r.rmse},
                     {"relmse", r.relmse},
                     {"bias_estimate", r.bias},
                     {"relmse_truth", or_null(r.relmse_truth)},
                     {"relmse_truth_interior", or_null(r.relmse_truth_interior)}});
  }
  // The truth: its cost, the noise left in it, and what the footprint model (the reference, the
  // multi-scale methods' limit) differs from it by.
  nlohmann::json jtruth = nullptr;
  if (o.truth_spp > 0)
    jtruth = {
        {"method", "brute-path"},
        {"spp", o.truth_spp},
        {"seeds", {truth_seeds[0], truth_seeds[1]}},
        {"cached", truth_seconds == 0},
        {"seconds", truth_seconds},
        {"files", {truth_cached[0].string(), truth_cached[1].string()}},
        {"noise_relmse", 0.25 * relmse_between(truth_half[0], truth_half[1], truth, every_pixel)},
        {"noise_relmse_interior",
         0.25 * relmse_between(truth_half[0], truth_half[1], truth, compared)},
        {"reference_relmse", against_truth(reference, every_pixel)},
        {"reference_relmse_interior", against_truth(reference, compared)}};
  nlohmann::json doc = {{"scene", o.scene},
                        {"resolution", {scene.camera.width, scene.camera.height}},
                        {"pixels_compared", pixels_compared},
                        {"reference",
                         {{"method", "reference"},
                          {"spp", ref_options.spp},
                          {"cached", reference_seconds == 0},
                          {"seconds", reference_seconds},
                          {"file", cached.string()}}},
                        {"truth", jtruth},
                        {"warmup", warmup},
                        {"rows", jrows},
                        {"summary", summary},
                        {"near_field", near_field},
                        {"tables", tables},
                        {"grid", grid}};
  formats::write_text_atomically(out / "error-time.csv", csv);
  formats::write_text_atomically(
      out / "error-time.json",
      doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  bool plotted = false;
  if (!o.no_plots) {
    // $CLOTHBAKE_PLOT_SCRIPT_DIR, else the source tree this file was compiled from.
    const char* env = std::getenv("CLOTHBAKE_PLOT_SCRIPT_DIR");
    const fs::path script =
        (env ? fs::path(env) : fs::path(CLOTHBAKE_SOURCE_DIR) / "scripts") / "plot_error_time.py";
    const std::string python =
        fs::exists("/usr/bin/python3") ? std::string("/usr/bin/python3") : std::string("python3");
    const std::string command = python + " '" + script.string() + "' '" + out.string() + "'";
    plotted = std::system(command.c_str()) == 0;
    if (!plotted)
      warn("report: plotting failed (python3-matplotlib missing?); the CSV and JSON are written");
  }

  ReportOutput result;
  std::string& text = result.summary;
  text += fmt::sprintf("error against run time: %s, %dx%d, reference %s\n",
                       terminal_safe(o.scene).c_str(), scene.camera.width, scene.camera.height,
                       reference_seconds == 0 ? "from the cache"
                                              : fmt::format("{:.3g} s", reference_seconds).c_str());
  if (o.truth_spp > 0)
    text += fmt::sprintf(
        "  path-traced truth: brute-path at %u spp, %s; its noise relMSE %.3g; the reference "
        "(the footprint model's limit) against it: relMSE %.4g (%.4g on the compared pixels)\n",
        o.truth_spp,
        truth_seconds == 0 ? "from the cache" : fmt::format("{:.3g} s", truth_seconds).c_str(),
        jtruth["noise_relmse"].get<double>(), jtruth["reference_relmse"].get<double>(),
        jtruth["reference_relmse_interior"].get<double>());
  text += fmt::sprintf(
      "  relMSE against the reference over %zu of %d pixels (silhouettes and shadow edges left "
      "out)%s\n",
      pixels_compared, scene.camera.width * scene.camera.height,
      o.truth_spp > 0 ? "; against the truth over every pixel and over those" : "");
  if (o.truth_spp > 0) {
    text += fmt::sprintf("  %-17s %5s %10s %12s %12s %12s %12s\n", "method", "spp", "seconds",
                         "vs truth", "(interior)", "vs ref.", "bias est.");
    for (const Row& r : rows)
      text +=
          fmt::sprintf("  %-17s %5u %10.3g %12.4g %12.4g %12.4g %12.3g\n", r.method.c_str(), r.spp,
                       r.seconds, r.relmse_truth, r.relmse_truth_interior, r.relmse, r.bias);
  } else {
    text += fmt::sprintf("  %-17s %5s %10s %12s %12s\n", "method", "spp", "seconds", "relMSE",
                         "bias est.");
    for (const Row& r : rows)
      text += fmt::sprintf("  %-17s %5u %10.3g %12.4g %12.3g\n", r.method.c_str(), r.spp, r.seconds,
                           r.relmse, r.bias);
  }
  if (summary.contains("equal_error_speedup")) {
    const std::string bound = summary["equal_error_speedup_bound"].get<std::string>();
    text += fmt::sprintf(
        "  multi-scale at %u spp against brute force: %s%.2fx the speed at equal error%s\n",
        operating->spp,
        bound == "lower"   ? ">"
        : bound == "upper" ? "<"
                           : "",
        summary["equal_error_speedup"].get<double>(),
        bound == "upper"   ? " (brute force's fastest render was already more accurate)"
        : bound == "lower" ? " (brute force never got there in the sweep)"
                           : "");
  }
  if (summary.contains("pairs"))
    for (const auto& pair : summary["pairs"]) {
      if (pair["method"] != "multiscale") continue;
      auto bound = [&](const char* key) {
        const std::string b = pair[key].get<std::string>();
        return b == "lower" ? ">" : b == "upper" ? "<" : b == "extrapolated" ? "~" : "";
      };
      text += fmt::sprintf(
          "  multi-scale at %u spp against %s at equal error (judged by the %s): %s%.3gx in time, "
          "%s%.3gx in samples per pixel\n",
          pair["spp"].get<uint32_t>(), pair["against"].get<std::string>().c_str(),
          pair["judge"] == "truth" ? "path-traced truth" : "reference",
          bound("equal_error_speedup_bound"), pair["equal_error_speedup"].get<double>(),
          bound("equal_error_spp_ratio_bound"), pair["equal_error_spp_ratio"].get<double>());
    }
  if (!tables.is_null())
    for (const auto& [name, t] : tables["methods"].items())
      text += fmt::sprintf(
          "  %s at %u spp, compressed against raw tables: relMSE %.3g (against the reference: "
          "raw %.4g, compressed %.4g)\n",
          name.c_str(), tables["spp"].get<uint32_t>(), t["relmse_compressed_vs_raw"].get<double>(),
          t["relmse_raw"].get<double>(), t["relmse_compressed"].get<double>());
  if (!near_field.is_null())
    text += fmt::sprintf(
        "  near field (%s, ray-traced relief): relMSE %.4g with parallax offsets, %.4g "
        "without\n",
        near_field["object"].get<std::string>().c_str(),
        near_field["relmse_parallax_model"].get<double>(),
        near_field["relmse_without_offsets"].get<double>());
  // The plots are listed only when they were drawn.
  text += fmt::sprintf("  %s/{error-time.csv,error-time.json%s}\n", terminal_safe(o.output).c_str(),
                       plotted ? ",error-time.png,grid.png" : "");
  result.doc = std::move(doc);
  return result;
}

}  // namespace clothbake::reports

// clothbake report error-time SCENE.toml -o DIR (report_error_time.hpp; docs/rendering.md,
// "Error against run time").
#include "bake/cli/report_error_time.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "bake/cli/command.hpp"
#include "bake/cli/scene_bake.hpp"
#include "bake/inputs/fabric_files.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "common/version.hpp"
#include "render/image_output.hpp"
#include "render/renderer.hpp"

namespace clothbake::cli {
namespace {

namespace fs = std::filesystem;

struct Row {
  std::string method;
  uint32_t spp = 0;
  double seconds = 0, rmse = 0, relmse = 0, bias = 0;
  render::RenderResult image;
};

// relMSE (mean over channels of pixels whose reference is not black of ((x - r) / r)^2) and RMSE.
void errors(const render::RenderResult& a, const render::RenderResult& ref, double* relmse,
            double* rmse) {
  double rel = 0, abs2 = 0;
  std::size_t count = 0;
  for (std::size_t k = 0; k < ref.rgb.size(); ++k) {
    const double d = double(a.rgb[k]) - ref.rgb[k];
    abs2 += d * d;
    if (ref.rgb[k] > 1e-6) {
      rel += (d / ref.rgb[k]) * (d / ref.rgb[k]);
      ++count;
    }
  }
  *relmse = count ? rel / count : 0;
  *rmse = ref.rgb.empty() ? 0 : std::sqrt(abs2 / ref.rgb.size());
}

// relMSE(spp) = bias^2 + c / spp, least squares over a method's sweep: the bias estimate b.
double fitted_bias(const std::vector<const Row*>& rows) {
  if (rows.size() < 2) return 0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = rows.size();
  for (const Row* r : rows) {
    const double x = 1.0 / r->spp, y = r->relmse;
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double c = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double b = (sy - c * sx) / n;
  return b > 0 ? std::sqrt(b) : 0;
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

void write_png(const fs::path& path, const render::RenderResult& r) {
  Image img(r.width, r.height, 3);
  for (std::size_t k = 0; k < r.rgb.size(); ++k)
    img.pixels[k] = float(render::srgb_encode(r.rgb[k]));
  write_image(path.string(), img, PixelType::UInt8);
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
  write_image(path.string(), img, PixelType::UInt8);
}

}  // namespace

int run_error_time_report(const ErrorTimeOptions& o) {
  std::vector<eval::Method> methods;
  for (const std::string& name : o.methods) {
    eval::Method m;
    if (!eval::parse_method(name.c_str(), &m) || m == eval::Method::Reference)
      throw CLI::ValidationError(
          "--methods", "unknown method '" + name + "' (multiscale, multiscale-paper, brute)");
    methods.push_back(m);
  }
  if (methods.empty()) throw CLI::ValidationError("--methods", "no method given");
  if (o.spp.empty()) throw CLI::ValidationError("--spp", "no spp given");
  for (uint32_t s : o.spp)
    if (s == 0) throw CLI::ValidationError("--spp", "every spp must be at least 1");
  const fs::path out(o.output);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw_input_error(o.output + ": exists and is not a directory");
  fs::create_directories(out / "images", ec);
  if (ec) throw_input_error(o.output + ": cannot create it (" + ec.message() + ")");

  inputs::LoadedScene loaded = inputs::load_scene(o.scene);
  bake_scene_fabrics(loaded, o.cache, true);
  const render::Scene& scene = loaded.scene;
  bool environment = false;
  for (const render::Light& l : scene.lights)
    environment |= l.type == render::LightType::Environment;

  // The reference: exact footprints; environment lights need many light samples. Cached by the
  // content of the scene, its assets and the reference settings.
  render::RenderOptions ref_options;
  ref_options.method = eval::Method::Reference;
  ref_options.spp = environment ? o.reference_spp : 1;
  ref_options.seed = o.seed + 1000003;
  std::string key = std::string(CLOTHBAKE_VERSION_STRING) + inputs::hash_file(o.scene) +
                    std::to_string(ref_options.spp);
  for (const render::Object& obj : scene.objects)
    if (!obj.asset.empty()) key += inputs::hash_file(obj.asset);
  const fs::path cache_dir = scene_cache_dir(o.cache);
  fs::create_directories(cache_dir, ec);
  const fs::path cached = cache_dir / ("reference-" + inputs::xxh64_hex(key) + ".exr");
  render::RenderResult reference;
  double reference_seconds = 0;
  if (fs::is_regular_file(cached, ec)) {
    const Image img = read_image(cached.string());
    reference.width = img.width;
    reference.height = img.height;
    reference.rgb = img.pixels;
  } else {
    reference = render::Renderer(scene, ref_options).render();
    reference_seconds = reference.stats.seconds;
    render::write_render_images(cached.string(), reference);
  }
  if (reference.width != scene.camera.width || reference.height != scene.camera.height)
    throw_input_error(cached.string() + ": cached reference of another size; delete it");

  std::vector<Row> rows;
  for (eval::Method m : methods)
    for (uint32_t spp : o.spp) {
      render::RenderOptions ro;
      ro.method = m;
      ro.spp = spp;
      ro.seed = o.seed;
      Row row;
      row.method = eval::method_name(m);
      row.spp = spp;
      row.image = render::Renderer(scene, ro).render();
      row.seconds = row.image.stats.seconds;
      errors(row.image, reference, &row.relmse, &row.rmse);
      rows.push_back(std::move(row));
    }
  for (eval::Method m : methods) {
    std::vector<const Row*> of;
    for (const Row& r : rows)
      if (r.method == eval::method_name(m)) of.push_back(&r);
    const double bias = fitted_bias(of);
    for (Row& r : rows)
      if (r.method == eval::method_name(m)) r.bias = bias;
  }
  auto curve = [&](const std::string& method) {
    std::vector<std::pair<double, double>> pts;  // (seconds, relmse) by seconds
    for (const Row& r : rows)
      if (r.method == method) pts.push_back({r.seconds, r.relmse});
    std::sort(pts.begin(), pts.end());
    return pts;
  };
  const Row* operating = nullptr;  // multiscale at 2 spp (or its nearest spp)
  for (const Row& r : rows)
    if (r.method == "multiscale" &&
        (!operating || std::abs(int(r.spp) - 2) < std::abs(int(operating->spp) - 2)))
      operating = &r;

  nlohmann::json summary = nlohmann::json::object();
  const auto brute = curve("brute");
  nlohmann::json grid = nlohmann::json::array();
  if (operating && !brute.empty()) {
    // Brute force's time at the operating point's error (log-log on the error axis), and its
    // error at the operating point's time.
    std::vector<std::pair<double, double>> by_error = brute;
    std::sort(by_error.begin(), by_error.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    const double t_equal = loglog_at(by_error, operating->relmse, true);
    const bool reached = std::isfinite(t_equal);
    const double t_brute = reached ? t_equal : brute.back().first;
    const double e_equal_time = loglog_at(brute, operating->seconds, false);
    summary["operating_point"] = {{"method", "multiscale"},
                                  {"spp", operating->spp},
                                  {"seconds", operating->seconds},
                                  {"relmse", operating->relmse}};
    summary["pairs"] = nlohmann::json::array();
    for (const Row& r : rows) {
      if (r.method == "brute" || r.spp != operating->spp) continue;
      const double t = loglog_at(by_error, r.relmse, true);
      const double e = loglog_at(brute, r.seconds, false);
      summary["pairs"].push_back(
          {{"method", r.method},
           {"against", "brute"},
           {"spp", r.spp},
           {"equal_error_speedup", (std::isfinite(t) ? t : brute.back().first) / r.seconds},
           {"equal_error_speedup_is_lower_bound", !std::isfinite(t)},
           {"equal_time_error_ratio",
            std::isfinite(e) ? nlohmann::json(e / r.relmse) : nlohmann::json(nullptr)}});
    }
    summary["equal_error_speedup"] = t_brute / operating->seconds;
    summary["equal_error_speedup_is_lower_bound"] = !reached;
    summary["brute_at_equal_error"] = {{"seconds", reached ? nlohmann::json(t_equal) : nullptr}};
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
    write_png(out / "images" / "reference.png", reference);
    grid.push_back({{"label", "reference"}, {"image", "images/reference.png"}});
    auto panel = [&](const Row* r, const std::string& name, const std::string& label) {
      write_png(out / "images" / (name + ".png"), r->image);
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

  // CSV and JSON.
  std::string csv = "scene,method,spp,seconds,rmse,relmse,bias_estimate\n";
  nlohmann::json jrows = nlohmann::json::array();
  for (const Row& r : rows) {
    csv +=
        fmt::format("{},{},{},{:.6g},{:.6g},{:.6g},{:.6g}\n", fs::path(o.scene).filename().string(),
                    r.method, r.spp, r.seconds, r.rmse, r.relmse, r.bias);
    jrows.push_back({{"method", r.method},
                     {"spp", r.spp},
                     {"seconds", r.seconds},
                     {"rmse", r.rmse},
                     {"relmse", r.relmse},
                     {"bias_estimate", r.bias}});
  }
  nlohmann::json doc = {{"scene", o.scene},
                        {"resolution", {scene.camera.width, scene.camera.height}},
                        {"reference",
                         {{"method", "reference"},
                          {"spp", ref_options.spp},
                          {"cached", reference_seconds == 0},
                          {"seconds", reference_seconds},
                          {"file", cached.string()}}},
                        {"rows", jrows},
                        {"summary", summary},
                        {"grid", grid}};
  std::ofstream(out / "error-time.csv") << csv;
  std::ofstream(out / "error-time.json") << doc.dump(2) << "\n";
  if (!o.no_plots) {
    // $CLOTHBAKE_PLOT_SCRIPT_DIR, else the source tree this file was compiled from.
    const char* env = std::getenv("CLOTHBAKE_PLOT_SCRIPT_DIR");
    const fs::path script =
        (env ? fs::path(env)
             : fs::path(__FILE__).parent_path().parent_path().parent_path() / "scripts") /
        "plot_error_time.py";
    const std::string python =
        fs::exists("/usr/bin/python3") ? std::string("/usr/bin/python3") : std::string("python3");
    const std::string command = python + " '" + script.string() + "' '" + out.string() + "'";
    if (std::system(command.c_str()) != 0)
      warn("report: plotting failed (python3-matplotlib missing?); the CSV and JSON are written");
  }

  if (o.json) {
    print_json(doc);
    return 0;
  }
  std::printf("error against run time: %s, %dx%d, reference %s\n", o.scene.c_str(),
              scene.camera.width, scene.camera.height,
              reference_seconds == 0 ? "from the cache"
                                     : fmt::format("{:.3g} s", reference_seconds).c_str());
  std::printf("  %-17s %5s %10s %12s %12s\n", "method", "spp", "seconds", "relMSE", "bias est.");
  for (const Row& r : rows)
    std::printf("  %-17s %5u %10.3g %12.4g %12.3g\n", r.method.c_str(), r.spp, r.seconds, r.relmse,
                r.bias);
  if (summary.contains("equal_error_speedup"))
    std::printf("  multi-scale at %u spp against brute force: %s%.2fx faster at equal error\n",
                operating->spp,
                summary["equal_error_speedup_is_lower_bound"].get<bool>() ? ">" : "",
                summary["equal_error_speedup"].get<double>());
  std::printf("  %s/{error-time.csv,error-time.json,error-time.png,grid.png}\n", o.output.c_str());
  return 0;
}

}  // namespace clothbake::cli

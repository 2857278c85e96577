// The baked cases of `report stability` (stability_rows.hpp; docs/hardening.md, "Stability
// report"): fabrics with a u-only height profile, each baked in a child process, then queried
// against direct computations (ray casts of the profile, direct sums, verify/).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "bake/inputs/map_limits.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/reports/stability_profile.hpp"
#include "bake/reports/stability_rows.hpp"
#include "bake/stages/stages.hpp"
#include "common/child_process.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "formats/writer/valid_asset.hpp"
#include "model/directions.hpp"
#include "model/splitmix64.hpp"
#include "verify/compressed_verify.hpp"
#include "verify/radiance_verify.hpp"

namespace clothbake::reports::stability {
namespace {

namespace fs = std::filesystem;

struct BakedCase {
  std::string name, parameter;
  Fabric fabric;
  int footprints = 24;
};

// What a bake left behind for the queries.
struct BakeOutcome {
  std::string path, failure;
  std::vector<std::string> warnings;
  double seconds = 0;
};

std::string case_path(const BakedCase& c, const std::string& scratch) {
  return (fs::path(scratch) / (c.name + "-" + c.parameter + ".cbk")).string();
}

// Bakes `c` in a child process (fork, common/child_process.hpp) with a time limit, so that a stage
// that never returns becomes a failed row instead of a hung report (it once did:
// docs/hardening.md, "The Embree hang"), and so that every case starts from a fresh process. The
// child writes the asset, its warnings (PATH.warnings, one a line) and any error (PATH.error), and
// leaves with _exit. Call before this process starts TBB threads.
BakeOutcome bake_in_child(const BakedCase& c, const std::string& scratch, int timeout_seconds) {
  BakeOutcome out;
  out.path = case_path(c, scratch);
  info(fmt::format("report stability: baking {} {} ({}^2)", c.name, c.parameter,
                   c.fabric.maps.resolution));
  const auto t0 = std::chrono::steady_clock::now();
  const ChildStart child = start_child([&]() {
    set_quiet(true);
    int code = 0;
    try {
      pipeline::BakeRequest request;
      request.fabric = c.fabric;
      request.output_path = out.path;
      request.force = true;
      compress::CompressRequest keep;
      keep.keep_raw = true;  // the compressed forms a renderer reads, and the raw ones to verify
      request.seeds.put(stages::kCompressSettingsArtifact, keep);
      pipeline::bake(request, stages::bake_stages());
    } catch (const std::exception& e) {
      std::ofstream(out.path + ".error") << e.what();
      code = 1;
    }
    std::ofstream w(out.path + ".warnings");
    for (std::string line : take_warnings()) {
      std::replace(line.begin(), line.end(), '\n', ' ');
      w << line << '\n';
    }
    w.close();
    return code;
  });
  if (!child.ok()) {
    out.failure = "fork failed";
    return out;
  }
  const ChildWait waited = wait_child(child.pid, timeout_seconds);
  if (waited.timed_out)
    out.failure = fmt::format("bake timed out after {} s (killed)", timeout_seconds);
  else if (!waited.ended)
    out.failure =
        fmt::format("lost track of the bake process (waitpid: {})", std::strerror(waited.error));
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ifstream w(out.path + ".warnings");
  for (std::string line; std::getline(w, line);)
    if (!line.empty()) out.warnings.push_back(line);
  std::ifstream e(out.path + ".error");
  std::string error((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  if (!error.empty()) out.failure = "bake failed: " + error;
  if (out.failure.empty() && waited.ended && !child_succeeded(waited.status))
    out.failure = "bake process ended abnormally";
  return out;
}

void baked_rows(Report& report, const BakedCase& c, const BakeOutcome& baked) {
  const Fabric& fabric = c.fabric;
  const int n = fabric.maps.resolution;
  std::vector<std::string> warnings = baked.warnings;
  std::optional<reader::Asset> opened;
  std::string failure = baked.failure;
  if (failure.empty()) try {
      opened.emplace(formats::open_valid_asset(baked.path));
    } catch (const Error& e) {
      failure = e.what();
    }
  auto row_of = [&](const std::string& quantity, const std::string& direct) {
    StabilityRow row;
    row.case_name = c.name;
    row.parameter = c.parameter;
    row.quantity = quantity;
    row.direct = direct;
    return row;
  };
  {
    StabilityRow row = row_of("bake + validate", "");
    row.warnings = warnings;
    Sample s;
    s.q = failure.empty() ? 0.0 : NAN;
    if (!failure.empty()) row.warnings.push_back("failed: " + failure);
    report.add_row(std::move(row), {s});
  }
  if (!opened) return;
  const reader::Asset& asset = *opened;

  // Parallax: every texel at every bin centre, raw and compressed, against the direct ray cast;
  // footprint means against direct sums of the per-texel answers.
  std::vector<double> profile(static_cast<std::size_t>(n));
  for (int x = 0; x < n; ++x)
    profile[std::size_t(x)] = double(fabric.maps.height[std::size_t(x)]);
  const double range = *std::max_element(profile.begin(), profile.end()) -
                       *std::min_element(profile.begin(), profile.end());
  for (auto source : {reader::ParallaxSource::Raw, reader::ParallaxSource::Compressed}) {
    const bool raw = source == reader::ParallaxSource::Raw;
    reader::ParallaxView view;
    StabilityRow depth_row = row_of(raw ? "parallax_depth (raw)" : "parallax_depth (compressed)",
                                    "ray cast of the profile between texel centres");
    StabilityRow foot_row =
        row_of(raw ? "parallax_footprint (raw)" : "parallax_footprint (compressed)",
               "area-weighted sum of the per-texel depths");
    const reader::Status st = view.open(asset, source);
    if (!st.ok()) {
      depth_row.warnings.push_back(std::string("parallax view: ") + st.message());
      report.add_row(std::move(depth_row), {Sample{NAN}});
      continue;
    }
    const int dirs = int(view.dirs());
    const model::DirectionGrid<double> grid{dirs, view.info().min_cos};
    double step_max = 0;
    for (int b = 0; b < dirs * dirs; ++b)
      step_max = std::max(step_max, view.depth_step(uint32_t(b)));
    // Per texel: the query quantises r to the bin's step, so the error bound is step / 2 plus the
    // ray caster's float rounding; errors are relative to the relief's range (flat: exactly 0).
    depth_row.rel_floor = foot_row.rel_floor = std::max(range, 1e-300);
    depth_row.tolerance = range > 0 ? (step_max / 2) / range + 1e-5 : 0.0;
    // Footprint means: exact integer SAT sums, then the covered fractions in double. Measured
    // 6e-11 of the relief at 256^2 and 2.8e-9 at 2048^2 (growing with the table, as a cancellation
    // of prefix sums of up to N^2 x 65535 codes would); 1e-7 of the relief is below 1e-4 texel of
    // Eq. 2 offset at 2048^2.
    foot_row.tolerance = range > 0 ? 1e-7 : 0.0;
    std::vector<Sample> depth_samples, foot_samples;
    // The project's generator: the same footprints on every platform and standard library.
    model::SplitMix64 rng(fabric.bake.seed);
    const int rows_checked = std::min(n, 4);  // the profile is constant in v
    for (int j = 0; j < dirs; ++j)
      for (int i = 0; i < dirs; ++i) {
        const Vec3d o = grid.bin_center(i, j);
        const double v[3] = {o.x, o.y, o.z};
        for (int y = 0; y < rows_checked; ++y)
          for (int x = 0; x < n; ++x) {
            reader::ParallaxSample ps;
            Sample s;
            s.nonnegative = false;
            if (view.depth(x, y * (n / rows_checked), v, &ps).ok()) {
              s.q = ps.r;
              s.d = report.perturb(direct_depth(profile, x, o), range > 0 ? range : 1.0);
            } else {
              s.q = NAN;
            }
            depth_samples.push_back(s);
          }
        // Footprints: sub-texel, one texel at the far corner, a few sizes, a whole tile, more.
        const int bin = j * dirs + i;
        if ((i + j) % 3 != 0 && n > 64) continue;  // large tables: a third of the directions
        std::vector<reader::Footprint> rects = {{n - 0.3, n - 0.3, n - 0.1, n - 0.05},
                                                {n - 1.0, n - 1.0, double(n), double(n)},
                                                {0, 0, double(n), double(n)},
                                                {-0.5 * n, 0.25, 1.0 * n, 1.5 * n}};
        for (int k = 0; k < c.footprints; ++k) {
          const double side = std::min(double(n), std::pow(2.0, 6 * rng.uniform()) * 0.37);
          const double x0 = (rng.uniform() * 3 - 1) * n, y0 = (rng.uniform() * 3 - 1) * n;
          rects.push_back({x0, y0, x0 + side, y0 + side * (0.5 + rng.uniform())});
        }
        for (const reader::Footprint& rect : rects) {
          reader::ParallaxSample ps;
          Sample s;
          s.nonnegative = false;
          if (!view.footprint_depth(rect, v, &ps).ok()) {
            s.q = NAN;
            foot_samples.push_back(s);
            continue;
          }
          double sum = 0;
          const long long xa = (long long)std::floor(rect.x0), xb = (long long)std::ceil(rect.x1);
          const long long ya = (long long)std::floor(rect.y0), yb = (long long)std::ceil(rect.y1);
          // Sum per column (the depth of a column depends on x only here, but the query does
          // not know that: the direct sum still visits the rows once per distinct wrap).
          for (long long y = ya; y < yb; ++y) {
            const double wy = std::min(rect.y1, double(y + 1)) - std::max(rect.y0, double(y));
            if (wy <= 0) continue;
            double row_sum = 0;
            for (long long x = xa; x < xb; ++x) {
              const double wx = std::min(rect.x1, double(x + 1)) - std::max(rect.x0, double(x));
              if (wx > 0) row_sum += wx * view.bin_depth(uint32_t(bin), x, y);
            }
            sum += wy * row_sum;
          }
          const double area = (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
          s.q = ps.r;
          s.d = report.perturb(sum / area, range > 0 ? range : 1.0);
          foot_samples.push_back(s);
        }
      }
    report.add_row(std::move(depth_row), depth_samples);
    report.add_row(std::move(foot_row), foot_samples);
  }

  // Visibility: finite, in [0, 1]; on the flat field 1 wherever the light is above the horizon
  // (nothing occludes), measured against that.
  {
    reader::VisibilityAsgView view;
    const bool flat = range == 0;
    StabilityRow row =
        row_of("visibility (finite, in [0,1])", flat ? "1 (a flat field occludes nothing)" : "");
    std::vector<Sample> samples;
    if (!view.open(asset).ok()) {
      samples.push_back(Sample{NAN});
    } else {
      const int step = std::max(1, n / 16);
      for (int y = 0; y < n; y += step)
        for (int x = 0; x < n; x += step)
          for (double ci : kCosines)
            for (double phi : {0.0, 1.3, 3.0, 4.4}) {
              const Vec3d w = direction(ci, phi);
              const double wv[3] = {w.x, w.y, w.z};
              double v = NAN;
              Sample s;
              s.q = view.visibility(x, y, wv, &v).ok() && v >= 0 && v <= 1 ? v : NAN;
              if (flat && ci >= 0.1) s.d = report.perturb(1.0, 1.0);
              samples.push_back(s);
            }
      if (flat) {
        row.tolerance = 0.05;  // the ASG fit of a constant (the fit error the bake reports)
        row.rel_floor = 1;
      }
    }
    report.add_row(std::move(row), samples);
  }

  // Integral-Radiance tables: the raw tables' footprint sums against direct sums of the texels'
  // bin values (verify/radiance_verify.hpp, (a)); the directional error (b) and the compressed
  // tables' footprint error against raw (reported only: they are approximations by design).
  try {
    verify::RadianceVerifyOptions ro;
    ro.samples = n > 64 ? 40 : 140;
    ro.seed = fabric.bake.seed;
    const verify::RadianceVerifyReport rv = verify::verify_radiance(asset, fabric, ro);
    for (const verify::KindReport& k : rv.kinds) {
      StabilityRow sat = row_of("radiance_footprint (raw, " + k.kind + ")",
                                "sum over the covered texels of their bin values (verify)");
      sat.tolerance = ro.max_rel_error;
      std::vector<double> errors;
      for (const verify::ErrorStats& e : k.sat)
        errors.push_back(e.max), sat.n_queries += uint64_t(e.values);
      report.add_relative_row(std::move(sat), errors);
      if (!k.directional.empty()) {
        StabilityRow dir = row_of("radiance_directional (raw, " + k.kind + ")",
                                  "exact sum of I(x) D_x(h) over the covered texels (verify)");
        std::vector<double> de;
        for (const verify::ErrorStats& e : k.directional)
          de.push_back(e.max), dir.n_queries += uint64_t(e.values);
        report.add_relative_row(std::move(dir), de);
      }
    }
    if (verify::has_compressed_tables(asset)) {
      verify::CompressedVerifyOptions co;
      co.samples = n > 64 ? 100 : 400;
      co.seed = fabric.bake.seed;
      co.throughput = false;
      const verify::CompressedVerifyReport cv = verify::verify_compressed(asset, fabric, co);
      for (const verify::CompressedKindReport& k : cv.kinds) {
        StabilityRow row = row_of("radiance_footprint (compressed, " + k.kind + ")",
                                  "the raw tables' footprint sums (verify)");
        std::vector<double> errors;
        for (const verify::FootprintClassError& e : k.classes)
          errors.push_back(e.max_relative), row.n_queries += uint64_t(e.footprints);
        report.add_relative_row(std::move(row), errors);
      }
    }
  } catch (const Error& e) {
    StabilityRow row = row_of("radiance tables", "");
    row.warnings.push_back(e.what());
    report.add_row(std::move(row), {Sample{NAN}});
  }
}

}  // namespace

void baked_case_rows(Report& report, const StabilityOptions& options, const std::string& scratch) {
  std::vector<BakedCase> cases;
  cases.push_back({"flat", "height=0",
                   profile_fabric(
                       "flat", 16, [](double) { return 0.0; }, 8, 2)});
  for (double a : {0.01, 0.1, 1.0, 8.0, inputs::kMaxHeightTiles}) {
    const double amp = a;
    cases.push_back(
        {"relief", "amplitude=" + num(a),
         profile_fabric(
             "relief", 16, [amp](double u) { return amp * std::sin(2 * kPi * u); }, 8, 2)});
  }
  const int big = options.large ? 2048 : 256;
  BakedCase table{"table", fmt::format("resolution={}", big),
                  profile_fabric(
                      "table", big, [](double u) { return 0.02 * std::sin(2 * kPi * 3 * u); },
                      options.large ? 4 : 8, options.large ? 1 : 2)};
  table.footprints = 4;
  if (options.table_case) cases.push_back(std::move(table));
  // Every bake first, each in a child process, before this process runs any TBB code.
  std::vector<BakeOutcome> outcomes;
  for (const BakedCase& c : cases)
    outcomes.push_back(bake_in_child(c, scratch, c.fabric.maps.resolution > 256 ? 3600 : 60));
  for (std::size_t k = 0; k < cases.size(); ++k)
    baked_rows(report, cases[k], outcomes[k]);
}

}  // namespace clothbake::reports::stability

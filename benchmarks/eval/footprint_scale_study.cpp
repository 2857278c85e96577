// Multi-scale against footprint brute force at every footprint size (docs/evaluator.md, "Footprints
// below a period"; docs/performance.md, "Multi-scale at every scale"): for footprints from a
// twentieth of a weave repeat to a hundred repeats a side, each candidate form of the unbiased
// control variate at 2 spp against brute force swept over 1-512 spp, at equal error.
//
// Candidates (all unbiased; the same control variate g and residual f - g at x'_k(p), except the
// two shifted forms, whose residual pairs f(x'_k(p)) with a rank-0 g at a rigidly shifted point):
//   periods      the whole-period form alone (FootprintBase::WholePeriods), at every size (the
//                shipped estimator sampled footprints below about 0.71 repeat as brute force)
//   shifted      base (1/|P|) ∫ g0 over P + δ̄ (δ̄ the footprint's mean parallax offset; g0 the
//                control variate with each cluster's mean visibility, integrable over any
//                rectangle from the compressed tables' and the evaluator's summed-area tables),
//                residual f(x'_k(p)) - g0(p + δ̄) at the same stratified points (this study's code)
//   shifted-bin  the same with the drawn view bin's own mean offset δ̄_k
//   samples      no base: the integral of g_V over P by the cheap samples alone
//                (FootprintBase::None)
//   blocks       the block form (FootprintBase::Blocks): exact over the whole source blocks nearest
//                to P from the bin's block prefix sums, the rest by cheap samples
//   shipped      the evaluator's default (per footprint the whole-period or the block form, no
//                base above EvalOptions::max_remainder_fraction, brute force below 2 texels)
// A candidate's EvalOptions may follow its name, "name:key=value:...", keys visibility_samples,
// visibility_pilot, remainder_sample_scale, block_sum_rank, min_control_variate_side,
// max_remainder_fraction, attenuation_pilot (0: g_V's yarn attenuation everywhere) and
// texel_attenuation (1: the texel's own everywhere) (e.g. shipped:max_remainder_fraction=0.35).
//
// For each size: K footprints (sides size x N, aspect 1:2 .. 2:1), random positions; directions
// random on the upper hemisphere with cos >= 0.2 (--order random), or K/16 rows of 16 abutting
// footprints, one direction pair per row (--order scanline, a renderer's order for the timing).
// relMSE against the Reference method with the reports' floor (1 % of the mean reference); each
// candidate's time per estimate (one core); brute force's time and spp at the candidate's error
// interpolated log-log on its sweep: the equal-error speedup in time and in samples (the latter is
// the per-sample variance ratio at brute force's own stratification), and the fraction of the
// candidate's estimates sampled as brute force (1 by definition when every one is, bit for bit).
//
//   footprint_scale_study ASSET... [--sizes 0.05,0.1,...] [--footprints K] [--repeats R]
//                         [--order random|scanline] [--candidates a,b,...] [--seed S]
//                         [--csv OUT.csv] [--plot OUT.png]
// --plot draws the speedup against footprint size with scripts/plot_scale_study.py (looked up in
// $CLOTHBAKE_PLOT_SCRIPT_DIR, else the source tree's scripts/). Uses the evaluator's internal
// headers (the shifted forms); exit 2 on a bad argument or asset.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "eval/eval_data.hpp"
#include "eval/evaluator.hpp"
#include "eval/footprint_samples.hpp"
#include "eval/texel_shading.hpp"
#include "model/spongecake.hpp"

using namespace clothbake;
using namespace clothbake::eval;

namespace {

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "footprint_scale_study: %s\nusage: footprint_scale_study ASSET... [--sizes "
               "a,b,...] [--footprints K] [--repeats R] [--order random|scanline] "
               "[--candidates a,b,...] [--seed S] [--csv OUT.csv] [--plot OUT.png]\n",
               why.c_str());
  std::exit(2);
}

std::vector<double> number_list(const char* text, const char* option) {
  std::vector<double> out;
  for (const char* s = text; *s;) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (end == s || !std::isfinite(v) || v <= 0) usage(std::string(option) + " needs numbers > 0");
    out.push_back(v);
    s = *end == ',' ? end + 1 : end;
    if (*end != ',' && *end != '\0') usage(std::string(option) + " is a comma-separated list");
  }
  if (out.empty()) usage(std::string(option) + " is empty");
  return out;
}

struct Config {
  Footprint footprint;
  double wi[3], wo[3];
  double reference = 0, weight = 1;
};

struct Point {
  double spp = 0, seconds = 0, relmse = 0;
};

// The shifted forms: a rank-0 control variate g0 (each cluster's mean visibility, the visibility
// basis's component 0 at the light) whose integral over any rectangle comes from summed-area
// tables, evaluated at p + shift for the residual.
struct Shifted {
  const EvalData* data = nullptr;
  ShadingFrame frame;
  ActiveLobes lobes;
  double vbar[reader::kMaxVisibilityClusters] = {};
  Rgb specular_scale[reader::kMaxVisibilityClusters];
  Rgb diffuse_scale, sheen_scale, delta_scale;

  void prepare(const EvalData& d, const double wi[3], const double wo[3]) {
    data = &d;
    Status s;
    if (!make_frame(d, wi, wo, kAllLobes, &frame, &s)) usage(s.message());
    lobes = active_lobes(d, frame);
    const uint32_t clusters = d.cluster_count();
    if (d.basis.is_open()) {
      const model::DirectionGrid<double> grid{int(d.basis.dirs()), 0.0};
      const model::BinBilinear<double> b = grid.bilinear(frame.wi_light);
      for (uint32_t c = 0; c < clusters; ++c) {
        vbar[c] = 0.0;
        for (int q = 0; q < 4; ++q)
          vbar[c] += b.weight[q] * double(d.basis.component(c, 0, uint32_t(b.index[q])));
      }
    } else {
      for (uint32_t c = 0; c < clusters; ++c)
        vbar[c] = frame.mean_visibility[c];
    }
    const model::ClothBsdf<double> any(d.texel_params(0));
    const Rgb t_sheen = any.sheen_transmittance(frame.wo);
    const bool reflect = frame.wi.z * frame.wo.z > 0.0;
    for (uint32_t c = 0; c < clusters; ++c) {
      // Eq. 10's attenuation at the yarn's fibre turned normal to h, as the shipped g.
      model::TexelParams<double> params = d.yarn_fibre[d.cluster_yarn[c]];
      const double hh = dot(frame.h, frame.h);
      if (hh > 0.0) {
        const model::Vec3d t = params.tangent - frame.h * (dot(params.tangent, frame.h) / hh);
        if (dot(t, t) > 1e-12 * dot(params.tangent, params.tangent)) params.tangent = t;
      }
      const auto sggx = model::FibreSggx<double>::make(params.tangent, params.roughness);
      const double dh = sggx.D(frame.h);
      const double thick = std::max(params.optical_thickness, 0.0);
      const double f = reflect ? model::spongecake_reflection(sggx, thick, frame.wi, frame.wo)
                               : model::spongecake_transmission(sggx, thick, frame.wi, frame.wo);
      specular_scale[c] = d.cluster_albedo[c] * t_sheen * ((dh > 0 ? f / dh : 0.0) * frame.cos_i);
    }
    diffuse_scale = t_sheen * (frame.cos_i * 0.318309886183790671537767526745028724);
    sheen_scale = any.eval(frame.wi, frame.wo, 1.0).sheen * frame.cos_i;
    delta_scale = t_sheen;
  }

  // g0 at texel index t, channel mean.
  double g0(uint64_t t) const {
    const EvalData& d = *data;
    const uint32_t x = uint32_t(t % d.n), y = uint32_t(t / d.n);
    const uint32_t label = d.clusters.label(x, y);
    const double v = vbar[label], gap = d.maps.gap[t];
    Rgb g;
    if (lobes.specular) {
      int cluster = -1;
      const double value = d.specular.texel_value(lobes.h_bins, x, y, label, &cluster);
      if (cluster >= 0) g += specular_scale[cluster] * (value * vbar[cluster]);
    }
    if (lobes.diffuse)
      g += diffuse_scale * (texel_diffuse_albedo(d, t, lobes.diffuse_lobe) * gap) * v;
    if (lobes.sheen) g += sheen_scale * v;
    if (lobes.delta) g += delta_scale * ((1.0 - gap) * v);
    return g.mean();
  }

  // (1/|R|) ∫_R g0, channel mean, from the tables' footprint queries and the footprint sums.
  double mean_over(const Footprint& r) const {
    const EvalData& d = *data;
    const uint32_t clusters = d.cluster_count();
    const double area = (r.x1 - r.x0) * (r.y1 - r.y0);
    Rgb sum;
    if (lobes.specular) {
      double f[reader::kMaxVisibilityClusters];
      const double h[3] = {frame.h.x, frame.h.y, frame.h.z};
      if (!d.specular.tables->try_query_all(r, h, f)) std::abort();
      for (uint32_t c = 0; c < clusters; ++c)
        sum += specular_scale[c] * (f[c] * vbar[c]);
    }
    reader::FootprintPlan plan;
    if (!reader::make_footprint_plan(r, d.n, &plan)) std::abort();
    const SumChannels& layout = d.sums.layout();
    std::vector<double> s(layout.count());
    d.sums.integral(plan, 0, layout.count(), s.data());
    for (uint32_t c = 0; c < clusters; ++c) {
      if (lobes.diffuse) {
        const uint32_t first = lobes.diffuse_lobe == model::Lobe::DiffuseReflection
                                   ? layout.diffuse_r()
                                   : layout.diffuse_t();
        sum += diffuse_scale * Rgb(s[first + 3 * c], s[first + 3 * c + 1], s[first + 3 * c + 2]) *
               vbar[c];
      }
      if (lobes.sheen) sum += sheen_scale * (s[layout.area() + c] * vbar[c]);
      if (lobes.delta) sum += delta_scale * (s[layout.gap() + c] * vbar[c]);
    }
    return sum.mean() / area;
  }

  // One estimate at spp stratified points: base over P + shift (the footprint's mean offset, or
  // the drawn bin's), residual f(x'_k(p)) - g0(p + shift).
  double estimate(const Footprint& p, uint32_t spp, bool per_bin, Rng& rng) const {
    const EvalData& d = *data;
    const int bin = draw_view_bin(frame, rng.uniform());
    double sx = 0, sy = 0;
    const double view[3] = {frame.view.x, frame.view.y, frame.view.z};
    if (per_bin) {
      // The drawn bin's mean depth over P: the parallax SAT of a view at the bin's centre.
      const model::DirectionGrid<double> grid{int(d.parallax.dirs()), d.parallax.info().min_cos};
      const int b = frame.parallax_bins.index[bin];
      const model::Vec3d c = grid.bin_center(b % grid.n, b / grid.n);
      const double centre[3] = {c.x, c.y, c.z};
      reader::ParallaxSample mean;
      if (!d.parallax.footprint_depth(p, centre, &mean).ok()) std::abort();
      sx = mean.r * frame.bin_offset_per_depth[bin][0];
      sy = mean.r * frame.bin_offset_per_depth[bin][1];
    } else {
      reader::ParallaxSample mean;
      if (!d.parallax.footprint_depth(p, view, &mean).ok()) std::abort();
      sx = mean.offset[0] * d.n;
      sy = mean.offset[1] * d.n;
    }
    double value = mean_over({p.x0 + sx, p.y0 + sy, p.x1 + sx, p.y1 + sy});
    TexelShading shading;
    double residual = 0;
    stratified_points(p, spp, rng, [&](double x, double y) {
      int64_t tx = 0, ty = 0;
      bin_destination(d, frame, bin, x, y, &tx, &ty);
      shade_texel(d, frame, tx, ty, &shading);
      double f = 0;
      for (const Rgb& l : shading.lobes)
        f += l.mean();
      residual += f - g0(d.texel(int64_t(std::floor(x + sx)), int64_t(std::floor(y + sy))));
    });
    return value + residual / spp;
  }
};

struct Candidate {
  std::string name;
  int kind = 0;  // 0: an evaluator's Multiscale, 1: shifted, 2: shifted-bin
  EvalOptions options;
  bool texel_attenuation = false;  // g_V's attenuation the texel's own in every band
};

const char* kAllCandidates = "periods,shifted,shifted-bin,samples,blocks,shipped";

// A candidate's options after its name: "name:key=value:..." (the knobs a study sweeps).
void set_option(Candidate& c, const std::string& setting) {
  const size_t eq = setting.find('=');
  if (eq == std::string::npos) usage("candidate option " + setting + " is not key=value");
  const std::string key = setting.substr(0, eq);
  char* end = nullptr;
  const double value = std::strtod(setting.c_str() + eq + 1, &end);
  if (end == setting.c_str() + eq + 1 || *end != '\0' || !(value >= 0.0))
    usage("candidate option " + setting + ": not a number >= 0");
  EvalOptions& o = c.options;
  if (key == "visibility_samples")
    o.visibility_samples = uint32_t(value);
  else if (key == "visibility_pilot")
    o.visibility_pilot = value != 0.0;
  else if (key == "remainder_sample_scale")
    o.remainder_sample_scale = value;
  else if (key == "block_sum_rank")
    o.block_sum_rank = uint32_t(value);
  else if (key == "min_control_variate_side")
    o.min_control_variate_side = value;
  else if (key == "max_remainder_fraction")
    o.max_remainder_fraction = value;
  else if (key == "attenuation_pilot")
    o.attenuation_pilot = value != 0.0;
  else if (key == "texel_attenuation")  // set in every band after open (EvalData's decision)
    c.texel_attenuation = value != 0.0;
  else
    usage("unknown candidate option " + key);
}

Candidate make_candidate(const std::string& spec) {
  Candidate c;
  c.name = spec;
  const std::string name = spec.substr(0, spec.find(':'));
  if (name == "periods") {
    c.options.footprint_base = FootprintBase::WholePeriods;
    c.options.min_control_variate_side = 0.0;
  } else if (name == "shifted") {
    c.kind = 1;
  } else if (name == "shifted-bin") {
    c.kind = 2;
  } else if (name == "samples") {
    c.options.footprint_base = FootprintBase::None;
    c.options.min_control_variate_side = 0.0;
  } else if (name == "blocks") {
    c.options.footprint_base = FootprintBase::Blocks;
    c.options.min_control_variate_side = 0.0;
  } else if (name != "shipped") {
    usage("unknown candidate " + name + " (" + kAllCandidates + ")");
  }
  for (size_t s = spec.find(':'); s != std::string::npos;) {
    const size_t e = spec.find(':', s + 1);
    set_option(c, spec.substr(s + 1, e == std::string::npos ? e : e - s - 1));
    s = e;
  }
  return c;
}

// relMSE and time per estimate over every config, `repeats` estimates each.
template <class Estimate1>
Point measure(const std::vector<Config>& configs, double spp, int repeats, Estimate1 one) {
  double sq = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t c = 0; c < configs.size(); ++c)
    for (int k = 0; k < repeats; ++k) {
      const double rel = (one(c) - configs[c].reference) / configs[c].weight;
      sq += rel * rel;
    }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double count = double(configs.size()) * repeats;
  return {spp, seconds / count, sq / count};
}

// The sweep's `field` at relMSE `target`, log-log interpolated; -1 when it is not reached (the
// caller reports a lower bound from the slowest point), -2 when even the fastest is more accurate.
double at_error(const std::vector<Point>& sweep, double target, double Point::*field) {
  if (!sweep.empty() && sweep.front().relmse <= target) return -2;
  for (size_t k = 1; k < sweep.size(); ++k) {
    const Point &a = sweep[k - 1], &b = sweep[k];
    if (a.relmse >= target && b.relmse <= target) {
      const double u =
          (std::log(target) - std::log(a.relmse)) / (std::log(b.relmse) - std::log(a.relmse));
      return std::exp(std::log(a.*field) + u * (std::log(b.*field) - std::log(a.*field)));
    }
  }
  return -1;
}

std::string source_dir() {
  const std::string self = __FILE__;  // benchmarks/eval/footprint_scale_study.cpp
  const size_t cut = self.rfind("/benchmarks/");
  return cut == std::string::npos ? "." : self.substr(0, cut);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> assets;
  std::vector<double> sizes = {0.05, 0.1, 0.2, 0.35, 0.5, 0.7, 1.0, 1.5, 3.0, 10.0, 100.0};
  int footprints = 32, repeats = 24;
  uint64_t seed = 1;
  bool scanline = false;
  std::string csv_path, plot_path, candidates_text = kAllCandidates;
  for (int a = 1; a < argc; ++a) {
    const std::string opt = argv[a];
    if (opt.rfind("--", 0) != 0) {
      assets.push_back(opt);
      continue;
    }
    if (a + 1 >= argc) usage("missing value of " + opt);
    const char* v = argv[++a];
    if (opt == "--sizes")
      sizes = number_list(v, "--sizes");
    else if (opt == "--footprints")
      footprints = std::max(1, std::atoi(v));
    else if (opt == "--repeats")
      repeats = std::max(2, std::atoi(v));
    else if (opt == "--seed")
      seed = uint64_t(std::strtoull(v, nullptr, 10));
    else if (opt == "--order") {
      if (std::strcmp(v, "random") != 0 && std::strcmp(v, "scanline") != 0)
        usage("--order is random or scanline");
      scanline = std::strcmp(v, "scanline") == 0;
    } else if (opt == "--candidates")
      candidates_text = v;
    else if (opt == "--csv")
      csv_path = v;
    else if (opt == "--plot")
      plot_path = v;
    else
      usage("unknown option " + opt);
  }
  if (assets.empty()) usage("no asset");
  std::vector<Candidate> candidates;
  for (size_t s = 0; s <= candidates_text.size();) {
    const size_t e = std::min(candidates_text.find(',', s), candidates_text.size());
    candidates.push_back(make_candidate(candidates_text.substr(s, e - s)));
    s = e + 1;
  }
  if (!plot_path.empty() && csv_path.empty()) csv_path = plot_path + ".csv";
  FILE* csv = csv_path.empty() ? nullptr : std::fopen(csv_path.c_str(), "w");
  if (!csv_path.empty() && csv == nullptr) usage("cannot write " + csv_path);
  if (csv)
    std::fprintf(csv,
                 "asset,order,size_repeats,side_texels,candidate,relmse,us_per_estimate,"
                 "speedup_time,speedup_time_bound,speedup_spp,speedup_spp_bound,"
                 "brute_relmse_2spp,brute_fraction\n");

  for (const std::string& path : assets) {
    reader::Asset asset;
    Status s = asset.open_file(path.c_str());
    if (!s.ok()) usage(path + ": " + s.message());
    // One evaluator per candidate's options (and the brute force's, the default).
    Evaluator base;
    if (!(s = base.open(asset)).ok()) usage(path + ": " + s.message());
    std::vector<Evaluator> evaluators(candidates.size());
    for (size_t c = 0; c < candidates.size(); ++c)
      if (candidates[c].kind == 0) {
        if (!(s = evaluators[c].open(asset, candidates[c].options)).ok())
          usage(path + ": " + s.message());
        if (candidates[c].texel_attenuation)
          for (bool& pays : const_cast<EvalData*>(evaluator_data(evaluators[c]))->attenuation_pays)
            pays = true;
      }
    const EvalData& data = *evaluator_data(base);
    const double n = data.n;
    const std::string name =
        path.substr(path.rfind('/') == std::string::npos ? 0 : path.rfind('/') + 1);
    std::printf(
        "# %s: %g^2 texels, %u clusters, block grid %u^2, %s order, %d footprints x %d "
        "repeats\n",
        path.c_str(), n, data.cluster_count(), data.subperiod.blocks(),
        scanline ? "scanline" : "random", footprints, repeats);
    // The pilots' decisions at open, per band (lowest first): the visibility correction, and g_V's
    // attenuation (t: the texel's own, y: the yarn's).
    std::printf("# pilots: correction ");
    for (bool pays : data.visibility_pays)
      std::printf("%c", pays ? '1' : '0');
    std::printf(", attenuation ");
    for (bool pays : data.attenuation_pays)
      std::printf("%c", pays ? 't' : 'y');
    std::printf("\n");
    std::printf(
        "| repeats a side | candidate | relMSE at 2 spp | us / estimate | speedup in time | in "
        "samples | brute force |\n");
    std::printf("| --- | --- | --- | --- | --- | --- | --- |\n");
    for (double size : sizes) {
      // Configurations.
      Rng rng(seed);
      std::vector<Config> configs;
      double wi[3] = {0, 0, 1}, wo[3] = {0, 0, 1};
      auto hemisphere = [&](double* w) {
        const double z = 0.2 + 0.8 * rng.uniform(), phi = 6.283185307179586 * rng.uniform();
        const double r = std::sqrt(1.0 - z * z);
        w[0] = r * std::cos(phi);
        w[1] = r * std::sin(phi);
        w[2] = z;
      };
      double row_x = 0, row_y = 0;
      while (int(configs.size()) < footprints) {
        Config c;
        const double side = size * n;
        const double aspect = std::exp((rng.uniform() - 0.5) * std::log(4.0));
        const double w = side * std::sqrt(aspect), h = side / std::sqrt(aspect);
        if (!scanline || configs.size() % 16 == 0) {
          hemisphere(wi);
          hemisphere(wo);
          row_x = rng.uniform() * n;
          row_y = rng.uniform() * n;
        }
        std::copy(wi, wi + 3, c.wi);
        std::copy(wo, wo + 3, c.wo);
        const double x = scanline ? row_x : rng.uniform() * n;
        const double y = scanline ? row_y : rng.uniform() * n;
        c.footprint = {x, y, x + w, y + h};
        if (scanline) row_x += w;
        Estimate e;
        if (!(s = base.estimate(c.footprint, c.wi, c.wo, Method::Reference, 1, rng, kAllLobes, &e))
                 .ok())
          usage(s.message());
        c.reference = e.value.mean();
        if (c.reference > 1e-6) configs.push_back(c);
      }
      double mean_reference = 0;
      for (const Config& c : configs)
        mean_reference += c.reference / double(configs.size());
      for (Config& c : configs)
        c.weight = std::sqrt(c.reference * c.reference + 1e-4 * mean_reference * mean_reference);

      // Warm-up, untimed: what each evaluator builds on first use for these views.
      auto warm = [&](const Evaluator& ev) {
        Rng r(seed ^ 0x9e3779b97f4a7c15ull);
        for (const Config& c : configs)
          for (int k = 0; k < 16; ++k) {
            Estimate e;
            (void)ev.estimate(c.footprint, c.wi, c.wo, Method::Multiscale, 2, r, kAllLobes, &e);
            (void)ev.estimate(c.footprint, c.wi, c.wo, Method::Brute, 2, r, kAllLobes, &e);
          }
      };
      warm(base);
      for (size_t c = 0; c < candidates.size(); ++c)
        if (candidates[c].kind == 0) warm(evaluators[c]);

      std::vector<Point> brute;
      for (uint32_t spp : {1u, 2u, 4u, 8u, 16u, 32u, 64u, 128u, 256u, 512u}) {
        Rng r(seed + spp);
        brute.push_back(measure(configs, spp, repeats, [&](size_t c) {
          Estimate e;
          (void)base.estimate(configs[c].footprint, configs[c].wi, configs[c].wo, Method::Brute,
                              spp, r, kAllLobes, &e);
          return e.value.mean();
        }));
      }
      for (size_t k = 0; k < candidates.size(); ++k) {
        const Candidate& cand = candidates[k];
        Rng r(seed + 7);
        Point p;
        double fallbacks = 0;  // the fraction of estimates sampled as brute force
        if (cand.kind == 0) {
          const Evaluator& ev = evaluators[k];
          p = measure(configs, 2, repeats, [&](size_t c) {
            Estimate e;
            const Status st = ev.estimate(configs[c].footprint, configs[c].wi, configs[c].wo,
                                          Method::Multiscale, 2, r, kAllLobes, &e);
            if (!st.ok()) usage(st.message());
            fallbacks += e.counters.without_control_variate ? 1.0 : 0.0;
            return e.value.mean();
          });
          fallbacks /= double(configs.size()) * repeats;
        } else {
          // Warm-up, untimed: the parallax SATs of the directions the shifted forms query.
          for (size_t c = 0; c < configs.size(); ++c) {
            Shifted sh;
            sh.prepare(data, configs[c].wi, configs[c].wo);
            for (int w = 0; w < 16; ++w)
              (void)sh.estimate(configs[c].footprint, 2, cand.kind == 2, r);
          }
          // The per-estimate constants (the frame, the yarns' attenuations) count in the time:
          // prepare once more per estimate inside the timed loop.
          p = measure(configs, 2, repeats, [&](size_t c) {
            Shifted sh;
            sh.prepare(data, configs[c].wi, configs[c].wo);
            return sh.estimate(configs[c].footprint, 2, cand.kind == 2, r);
          });
        }
        const double tb = at_error(brute, p.relmse, &Point::seconds);
        const double sb = at_error(brute, p.relmse, &Point::spp);
        auto ratio = [&](double at, double Point::*field, double own, const char** bound) {
          *bound = at == -1 ? "lower" : at == -2 ? "upper" : "none";
          const double b = at == -1 ? brute.back().*field : at == -2 ? brute.front().*field : at;
          return b / own;
        };
        const char *tbound = nullptr, *sbound = nullptr;
        double st = ratio(tb, &Point::seconds, p.seconds, &tbound);
        double ss = ratio(sb, &Point::spp, 2.0, &sbound);
        if (fallbacks == 1.0) {  // every estimate brute force's, bit for bit: 1 by definition
          st = ss = 1.0;
          tbound = sbound = "brute";
        }
        auto mark = [](const char* bound) {
          return std::strcmp(bound, "lower") == 0   ? ">"
                 : std::strcmp(bound, "upper") == 0 ? "<"
                                                    : "";
        };
        std::printf("| %g | %s | %.4g | %.2f | %s%.2fx | %s%.1fx | %.0f %% |\n", size,
                    cand.name.c_str(), p.relmse, p.seconds * 1e6, mark(tbound), st, mark(sbound),
                    ss, fallbacks * 100);
        if (csv)
          std::fprintf(csv, "%s,%s,%g,%g,%s,%.6g,%.4f,%.4f,%s,%.4f,%s,%.6g,%.4f\n", name.c_str(),
                       scanline ? "scanline" : "random", size, size * n, cand.name.c_str(),
                       p.relmse, p.seconds * 1e6, st, tbound, ss, sbound, brute[1].relmse,
                       fallbacks);
      }
      std::fflush(stdout);
      if (csv) std::fflush(csv);
    }
  }
  if (csv) std::fclose(csv);
  if (!plot_path.empty()) {
    const char* dir = std::getenv("CLOTHBAKE_PLOT_SCRIPT_DIR");
    const std::string script =
        std::string(dir ? dir : (source_dir() + "/scripts").c_str()) + "/plot_scale_study.py";
    // Debian's interpreter (python3-matplotlib) when present, else whatever python3 is, as the
    // reports run their plot scripts.
    const std::string python =
        std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
    const std::string command =
        python + " '" + script + "' '" + csv_path + "' -o '" + plot_path + "'";
    if (std::system(command.c_str()) != 0)
      std::fprintf(stderr, "footprint_scale_study: plotting failed (%s)\n", command.c_str());
  }
  return 0;
}

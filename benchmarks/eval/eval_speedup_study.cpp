// Equal-error speedup of the multi-scale methods over brute force on random far-field footprints
// (docs/evaluator.md, "Speed"): for N random footprints (sides in [min, max] texels, random
// positions) and random reflection directions (cos >= 0.2 on both sides), the relative MSE
// against the Reference method of the multi-scale methods at 2 spp and of brute force over an spp
// sweep, each with its mean time per estimate (one core); brute force's time at the multi-scale
// error is interpolated on the log-log curve. relMSE has the reports' floor: (x - r)^2 / (r^2 +
// eps^2), eps = 1 % of the mean reference over the footprints.
//
//   eval_speedup_study ASSET [--footprints N] [--repeats K] [--min-side S] [--max-side S]
//                      [--remainder-scale K] [--max-remainder F] [--per-footprint] [--seed S]
//                      [--tables raw|compressed]
// --remainder-scale: EvalOptions::remainder_sample_scale; --max-remainder:
// EvalOptions::max_remainder_fraction. Besides the time, the equal-error ratio
// in samples: brute force's spp at the multi-scale error (log-log interpolation) over 2.
// Exit 2 on a bad argument or asset.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "eval/evaluator.hpp"

namespace {

using namespace clothbake;
using namespace clothbake::eval;

struct Config {
  Footprint footprint;
  double wi[3], wo[3];
  double reference;  // channel mean of the reference value
  double weight;     // sqrt(reference^2 + eps^2): the relative error's denominator
};

struct Point {
  double spp, seconds, relmse, bias2;
};

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "eval_speedup_study: %s\nusage: eval_speedup_study ASSET [--footprints N] "
               "[--repeats K] [--min-side S] [--max-side S] [--seed S] [--tables raw|compressed] "
               "[--remainder-scale K] [--max-remainder F] [--per-footprint]\n",
               why);
  std::exit(2);
}

double number(const char* text, const char* option) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v) || v <= 0)
    usage((std::string(option) + " needs a positive number").c_str());
  return v;
}

double mean3(const Rgb& c) {
  return (c.r + c.g + c.b) / 3.0;
}

// relMSE and time per estimate of `method` at `spp` over every config, K repeats each.
bool g_per_footprint = false;  // --per-footprint: one line per footprint (side, cosines, relMSE)

Point measure(const Evaluator& ev, const std::vector<Config>& configs, Method method, uint32_t spp,
              int repeats, uint64_t seed) {
  Rng rng(seed);
  // Warm-up, untimed: the tables the readers and the evaluator build on first use (the parallax
  // SATs of a direction bin, its block means) exist after a renderer's first pixels; building them
  // inside the timed loop would charge the whole build to these few estimates.
  for (const Config& c : configs) {
    Estimate e;
    Rng warm(seed ^ 0x9e3779b97f4a7c15ull);
    for (int k = 0; k < 16; ++k)  // every view bin the estimates may draw
      (void)ev.estimate(c.footprint, c.wi, c.wo, method, spp, warm, kAllLobes, &e);
  }
  double sq = 0, bias2 = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (const Config& c : configs) {
    double sum = 0, own = 0;
    for (int k = 0; k < repeats; ++k) {
      Estimate e;
      const Status s = ev.estimate(c.footprint, c.wi, c.wo, method, spp, rng, kAllLobes, &e);
      if (!s.ok()) usage(s.message());
      const double rel = (mean3(e.value) - c.reference) / c.weight;
      sq += rel * rel;
      own += rel * rel;
      sum += rel;
    }
    if (g_per_footprint && spp == 2)
      std::printf("  %-16s side %7.1f  wi.z %.2f wo.z %.2f  ref %.3g  relMSE %.4g\n",
                  method_name(method),
                  std::sqrt((c.footprint.x1 - c.footprint.x0) * (c.footprint.y1 - c.footprint.y0)),
                  c.wi[2], c.wo[2], c.reference, own / repeats);
    bias2 += (sum / repeats) * (sum / repeats);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double count = double(configs.size()) * repeats;
  return {double(spp), seconds / count, sq / count, bias2 / double(configs.size())};
}

// Brute force's time at relMSE `target`, log-log interpolated on the sweep; negative when the
// sweep never gets there (the caller reports a lower bound).
// The sweep's `field` (seconds or spp) at relMSE `target`, log-log interpolated; -1 when the sweep
// does not reach the target.
double at_error(const std::vector<Point>& sweep, double target, double Point::*field) {
  for (size_t k = 1; k < sweep.size(); ++k) {
    const Point &a = sweep[k - 1], &b = sweep[k];
    if (a.relmse >= target && b.relmse <= target) {
      const double u =
          (std::log(target) - std::log(a.relmse)) / (std::log(b.relmse) - std::log(a.relmse));
      return std::exp(std::log(a.*field) + u * (std::log(b.*field) - std::log(a.*field)));
    }
  }
  if (!sweep.empty() && sweep.front().relmse <= target) return sweep.front().*field;
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) usage("no asset");
  int footprints = 100, repeats = 64;
  double min_side = 32, max_side = 0, seed = 1;
  EvalOptions options;
  for (int a = 2; a < argc; ++a) {
    const std::string opt = argv[a];
    if (opt == "--per-footprint") {
      g_per_footprint = true;
      continue;
    }
    if (a + 1 >= argc) usage(("missing value of " + opt).c_str());
    const char* v = argv[++a];
    if (opt == "--footprints")
      footprints = int(number(v, "--footprints"));
    else if (opt == "--repeats")
      repeats = std::max(2, int(number(v, "--repeats")));
    else if (opt == "--min-side")
      min_side = number(v, "--min-side");
    else if (opt == "--max-side")
      max_side = number(v, "--max-side");
    else if (opt == "--seed")
      seed = number(v, "--seed");
    else if (opt == "--remainder-scale")
      options.remainder_sample_scale = number(v, "--remainder-scale");
    else if (opt == "--max-remainder")
      options.max_remainder_fraction = number(v, "--max-remainder");
    else if (opt == "--block-rank")
      options.block_sum_rank = uint32_t(std::atoi(v));
    else if (opt == "--block-bytes")
      options.max_block_sum_bytes = std::strtod(v, nullptr);
    else if (opt == "--base") {
      if (std::strcmp(v, "auto") == 0)
        options.footprint_base = FootprintBase::Auto;
      else if (std::strcmp(v, "periods") == 0)
        options.footprint_base = FootprintBase::WholePeriods;
      else if (std::strcmp(v, "blocks") == 0)
        options.footprint_base = FootprintBase::Blocks;
      else if (std::strcmp(v, "none") == 0)
        options.footprint_base = FootprintBase::None;
      else
        usage("--base is auto, periods, blocks or none");
    } else if (opt == "--tables") {
      if (std::strcmp(v, "raw") == 0)
        options.tables = TableChoice::Raw;
      else if (std::strcmp(v, "compressed") == 0)
        options.tables = TableChoice::Compressed;
      else
        usage("--tables is raw or compressed");
    } else
      usage(("unknown option " + opt).c_str());
  }
  reader::Asset asset;
  Evaluator ev;
  Status s = asset.open_file(argv[1]);
  if (s.ok()) s = ev.open(asset, options);
  if (!s.ok()) usage(s.message());
  const double n = ev.resolution();
  if (max_side == 0) max_side = 4 * n;
  if (max_side < min_side) usage("--max-side is below --min-side");

  Rng rng{uint64_t(seed)};
  std::vector<Config> configs;
  auto hemisphere = [&](double* w) {
    const double z = 0.2 + 0.8 * rng.uniform(), phi = 6.283185307179586 * rng.uniform();
    const double r = std::sqrt(1.0 - z * z);
    w[0] = r * std::cos(phi);
    w[1] = r * std::sin(phi);
    w[2] = z;
  };
  double reference_seconds = 0, texels = 0;
  while (int(configs.size()) < footprints) {
    Config c;
    const double side =
        std::exp(std::log(min_side) + rng.uniform() * std::log(max_side / min_side));
    const double aspect = std::exp((rng.uniform() - 0.5) * std::log(4.0));  // 1:2 .. 2:1
    const double x = rng.uniform() * n, y = rng.uniform() * n;
    c.footprint = {x, y, x + side * std::sqrt(aspect), y + side / std::sqrt(aspect)};
    hemisphere(c.wi);
    hemisphere(c.wo);
    Estimate e;
    const auto t0 = std::chrono::steady_clock::now();
    s = ev.estimate(c.footprint, c.wi, c.wo, Method::Reference, 1, rng, kAllLobes, &e);
    reference_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    texels += (c.footprint.x1 - c.footprint.x0) * (c.footprint.y1 - c.footprint.y0);
    if (!s.ok()) usage(s.message());
    c.reference = mean3(e.value);
    if (c.reference > 1e-6) configs.push_back(c);  // relative errors need a non-black reference
  }
  // relMSE as the renderer's reports define it (bake/reports/render_error.hpp): (x - r)^2 / (r^2 +
  // eps^2) with eps = 1 % of the mean reference, so that a few nearly black footprints do not
  // decide the mean.
  double mean_reference = 0;
  for (const Config& c : configs)
    mean_reference += c.reference / double(configs.size());
  for (Config& c : configs)
    c.weight = std::sqrt(c.reference * c.reference + 1e-4 * mean_reference * mean_reference);
  std::printf(
      "asset %s: %g^2 texels, %u clusters, %s tables; %d footprints of side %g..%g texels, "
      "%d repeats\n",
      argv[1], n, ev.cluster_count(), ev.table_source(), footprints, min_side, max_side, repeats);
  std::printf("reference: %.3g s per footprint on average\n", reference_seconds / footprints);
  std::printf("%-17s %6s %12s %12s %12s\n", "method", "spp", "us/estimate", "relMSE", "bias^2");
  std::vector<Point> brute;
  for (uint32_t spp : {2u, 4u, 8u, 16u, 32u, 64u, 128u, 256u, 512u}) {
    brute.push_back(measure(ev, configs, Method::Brute, spp, repeats, 100 + spp));
    const Point& p = brute.back();
    std::printf("%-17s %6u %12.3f %12.4g %12.3g\n", "brute", spp, p.seconds * 1e6, p.relmse,
                p.bias2);
  }
  for (Method m : {Method::Multiscale, Method::MultiscalePaper}) {
    const Point p = measure(ev, configs, m, 2, repeats, 7);
    const double tb = at_error(brute, p.relmse, &Point::seconds);
    const double sb = at_error(brute, p.relmse, &Point::spp);
    std::printf("%-17s %6d %12.3f %12.4g %12.3g   equal-error speedup %s%.1fx time, %s%.1fx spp\n",
                method_name(m), 2, p.seconds * 1e6, p.relmse, p.bias2, tb < 0 ? ">" : "",
                (tb < 0 ? brute.back().seconds : tb) / p.seconds, sb < 0 ? ">" : "",
                (sb < 0 ? brute.back().spp : sb) / 2.0);
  }
  return 0;
}

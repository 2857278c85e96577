// clothbake eval: one footprint estimate of the multi-scale evaluator on an asset, by any method,
// repeated for its standard error (docs/evaluator.md, "CLI").
//
//   clothbake eval ASSET --rect x0,y0,x1,y1 --wi x,y,z --wo x,y,z
//                  [--method multiscale|multiscale-paper|brute|reference] [--spp N] [--seed S]
//                  [--repeat K] [--lobes all|NAME[,NAME...]] [--tables auto|raw|compressed]
//                  [--sheen-convention published|converged] [--json]
//
// Exit codes: 1 bad arguments (naming the option), 2 missing file or a section the method needs,
// 3 invalid asset, 0 otherwise.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "common/error.hpp"
#include "eval/evaluator.hpp"
#include "formats/writer/open_asset.hpp"
#include "formats/writer/valid_asset.hpp"
#include "model/parameter_text.hpp"

namespace clothbake::cli {
namespace {

struct EvalCliOptions {
  std::string asset, rect, wi, wo, method = "multiscale", lobes = "all";
  eval::TableChoice tables = eval::TableChoice::Auto;
  std::string sheen_convention = "published";
  uint32_t spp = 2, repeat = 1;
  uint64_t seed = 1;
  bool json = false;
};

std::array<double, 4> parse_rect(const std::string& text) {
  NumberListRule rule;
  rule.expected = "x0,y0,x1,y1";
  rule.count = 4;
  const std::vector<double> v = parse_number_list(text, "--rect", rule);
  if (v[2] < v[0] || v[3] < v[1])
    throw CLI::ValidationError("--rect", "x1 must be >= x0 and y1 >= y0");
  return {v[0], v[1], v[2], v[3]};
}

eval::LobeMask parse_lobes(const std::string& text) {
  if (text == "all") return eval::kAllLobes;
  eval::LobeMask mask = 0;
  std::stringstream in(text);
  std::string name;
  while (std::getline(in, name, ',')) {
    model::Lobe lobe;
    if (!model::parse_lobe(name, lobe))
      throw CLI::ValidationError("--lobes", "unknown lobe '" + name +
                                                "' (all, specular_reflection, "
                                                "specular_transmission, diffuse_reflection, "
                                                "diffuse_transmission, delta_transmission, sheen)");
    mask |= eval::lobe_bit(lobe);
  }
  if (mask == 0) throw CLI::ValidationError("--lobes", "no lobe given");
  return mask;
}

nlohmann::json rgb(const eval::Rgb& c) {
  return nlohmann::json::array({c.r, c.g, c.b});
}

int run_eval(const EvalCliOptions& o) {
  eval::Method method;
  if (!eval::parse_method(o.method.c_str(), &method))
    throw CLI::ValidationError("--method", "unknown method '" + o.method + "'");
  if (o.spp == 0) throw CLI::ValidationError("--spp", "must be at least 1");
  if (o.repeat == 0) throw CLI::ValidationError("--repeat", "must be at least 1");
  if (double(o.spp) * double(o.repeat) > kMaxEvalSamples)
    throw CLI::ValidationError("--repeat", "--spp " + std::to_string(o.spp) + " x --repeat " +
                                               std::to_string(o.repeat) +
                                               " samples: at most 2^32 (4294967296) are accepted");
  const std::array<double, 4> r = parse_rect(o.rect);
  const std::array<double, 3> wi = parse_direction(o.wi, "--wi");
  const std::array<double, 3> wo = parse_direction(o.wo, "--wo");
  const eval::LobeMask mask = parse_lobes(o.lobes);
  eval::EvalOptions options;
  options.tables = o.tables;
  model::parse_sheen_convention(o.sheen_convention, options.sheen_convention);  // IsMember

  const reader::Asset asset = formats::open_valid_asset(o.asset);
  eval::Evaluator evaluator;
  formats::throw_if_failed(evaluator.open(asset, options), o.asset);
  const eval::Footprint footprint{r[0], r[1], r[2], r[3]};
  eval::Rng rng(o.seed);
  eval::Rgb sum, sum2, lobes[model::kLobeCount];
  eval::Estimate e;
  const auto start = std::chrono::steady_clock::now();
  for (uint32_t k = 0; k < o.repeat; ++k) {
    const reader::Status s =
        evaluator.estimate(footprint, wi.data(), wo.data(), method, o.spp, rng, mask, &e);
    if (s.code() == reader::ErrorCode::InvalidArgument)
      throw CLI::ValidationError("--rect", s.message());
    formats::throw_if_failed(s, o.asset);
    sum += e.value;
    sum2 += e.value * e.value;
    for (int l = 0; l < model::kLobeCount; ++l)
      lobes[l] += e.lobes[l];
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / o.repeat;
  const double k = o.repeat;
  const eval::Rgb mean = sum / k;
  eval::Rgb std_error;
  if (o.repeat > 1)
    for (int c = 0; c < 3; ++c) {
      double var = std::max(0.0, sum2[c] / k - mean[c] * mean[c]) * k / (k - 1.0);
      // Identical estimates (the reference, the direct path) leave only rounding in sum2.
      if (var <= 1e-24 * mean[c] * mean[c]) var = 0;
      (c == 0 ? std_error.r : c == 1 ? std_error.g : std_error.b) = std::sqrt(var / k);
    }
  const double texels = (r[2] - r[0]) * (r[3] - r[1]);
  if (o.json) {
    nlohmann::json parts = nlohmann::json::object();
    for (int l = 0; l < model::kLobeCount; ++l)
      if (mask & eval::lobe_bit(model::Lobe(l)))
        parts[model::lobe_name(model::Lobe(l))] = rgb(lobes[l] / k);
    nlohmann::json out = {{"asset", o.asset},
                          {"method", eval::method_name(method)},
                          {"spp", o.spp},
                          {"repeat", o.repeat},
                          {"seed", o.seed},
                          {"rect", {r[0], r[1], r[2], r[3]}},
                          {"wi", {wi[0], wi[1], wi[2]}},
                          {"wo", {wo[0], wo[1], wo[2]}},
                          {"tables", evaluator.table_source()},
                          {"value", rgb(mean)},
                          {"lobes", parts},
                          {"std_error", rgb(std_error)},
                          {"seconds_per_estimate", seconds},
                          {"footprint_side_texels", std::sqrt(texels)},
                          {"direct", e.counters.direct},
                          {"without_control_variate", e.counters.without_control_variate},
                          {"texel_evals", e.counters.texel_evals},
                          {"samples", e.counters.samples},
                          {"remainder_samples", e.counters.remainder_samples},
                          {"visibility_samples", e.counters.visibility_samples}};
    print_json(out);
    return 0;
  }
  std::printf("%s over [%g, %g) x [%g, %g) (%g x %g texels), %s tables, %u spp x %u:\n",
              eval::method_name(method), r[0], r[2], r[1], r[3], r[2] - r[0], r[3] - r[1],
              evaluator.table_source(), o.spp, o.repeat);
  std::printf("  value      (%.6g, %.6g, %.6g)", mean.r, mean.g, mean.b);
  if (o.repeat > 1)
    std::printf("  +- (%.3g, %.3g, %.3g) standard error", std_error.r, std_error.g, std_error.b);
  std::printf("\n");
  for (int l = 0; l < model::kLobeCount; ++l)
    if (mask & eval::lobe_bit(model::Lobe(l))) {
      const eval::Rgb v = lobes[l] / k;
      std::printf("  %-22s (%.6g, %.6g, %.6g)\n", model::lobe_name(model::Lobe(l)), v.r, v.g, v.b);
    }
  std::printf("  %.3g us per estimate%s\n", seconds * 1e6,
              e.counters.direct ? " (footprint below the direct threshold: exact texel sum)" : "");
  return 0;
}

const bool eval_registered = register_command(
    {"eval",
     "estimate the footprint average of the cloth BSDF (Eq. 5) by the multi-scale evaluator, brute "
     "force or the exact reference",
     [](CLI::App& app) -> Action {
       auto o = std::make_shared<EvalCliOptions>();
       add_asset_argument(app, o->asset);
       app.add_option("--rect", o->rect,
                      "footprint x0,y0,x1,y1 in texel units, half-open, any size, wraps")
           ->required();
       app.add_option("--wi", o->wi, "light direction x,y,z in the local frame (towards the light)")
           ->required();
       app.add_option("--wo", o->wo, "view direction x,y,z in the local frame (towards the viewer)")
           ->required();
       app.add_option("--method", o->method,
                      "multiscale (unbiased control variates, default), multiscale-paper (Eq. 8-10 "
                      "as printed), brute (per-sample parallax), reference (exact)")
           ->check(CLI::IsMember({"multiscale", "multiscale-paper", "brute", "reference"}));
       app.add_option("--spp", o->spp, "samples over the footprint per estimate (default 2)");
       app.add_option("--seed", o->seed, "seed of the sample sequence (default 1)");
       app.add_option("--repeat", o->repeat,
                      "independent estimates to average; their spread gives std_error (default 1)");
       app.add_option("--lobes", o->lobes,
                      "all, or a comma list of lobes of Eq. 4 to restrict every method to");
       add_tables_option(app, o->tables, "the multi-scale methods' ");
       app.add_option("--sheen-convention", o->sheen_convention,
                      "sheen table: published (Zeltner et al.'s, as Cycles ships it; default) or "
                      "converged (docs/sheen.md)")
           ->check(CLI::IsMember({"published", "converged"}));
       add_json_flag(app, o->json, "print the estimate as JSON on stdout");
       return [o] { return run_eval(*o); };
     }});

}  // namespace
}  // namespace clothbake::cli

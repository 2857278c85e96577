// clothbake query: answers the reader library's per-texel and footprint queries on an asset, for
// looking at a bake and for scripts (docs/raycast.md, "Queries").
//
//   clothbake query ASSET parallax   --dir x,y,z (--texel i,j | --rect x0,y0,x1,y1) [--json]
//   clothbake query ASSET visibility --texel i,j --dir x,y,z [--json]
//   clothbake query ASSET radiance   --lobe L [--cluster C] --h x,y,z --rect x0,y0,x1,y1
//                                    [--tables auto|raw|compressed] [--json]
//
// The radiance kind is radiance_query (bake/cli/radiance_query_command.hpp): F_c(rect, h) of
// the lobe's Integral-Radiance table from the raw or the compressed tables (the answer says which).
//
// Exit codes: 1 bad arguments (naming the option), 2 missing file or missing section, 3 invalid
// asset (layout or checksum), 0 otherwise.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/cli/radiance_query_command.hpp"
#include "common/error.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "formats/writer/open_asset.hpp"
#include "formats/writer/valid_asset.hpp"

namespace clothbake::cli {
namespace {

struct QueryOptions {
  std::string asset;
  std::string dir;
  std::string texel;
  std::string rect;
  std::string lobe;
  std::optional<uint32_t> cluster;
  std::string h;
  eval::TableChoice tables = eval::TableChoice::Auto;
  bool json = false;
};

const NumberListRule kTexel{
    .expected = "two comma-separated integers i,j", .count = 2, .integers = true};
const NumberListRule kRect{.expected = "four comma-separated numbers x0,y0,x1,y1", .count = 4};

nlohmann::json vec(const double* v, int n) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < n; ++i)
    a.push_back(v[i]);
  return a;
}

int query_parallax(const QueryOptions& o) {
  if (o.dir.empty()) throw CLI::ValidationError("--dir", "parallax queries need --dir x,y,z");
  if (o.texel.empty() == o.rect.empty())
    throw CLI::ValidationError("--texel",
                               "parallax queries need exactly one of --texel i,j and "
                               "--rect x0,y0,x1,y1");
  const std::array<double, 3> dir = parse_direction(o.dir, "--dir");
  std::vector<double> texel, rect;
  if (!o.texel.empty()) texel = parse_number_list(o.texel, "--texel", kTexel);
  if (!o.rect.empty()) {
    rect = parse_number_list(o.rect, "--rect", kRect);
    if (rect[2] < rect[0] || rect[3] < rect[1])
      throw CLI::ValidationError("--rect", "x1 must be >= x0 and y1 >= y0");
  }
  const reader::Asset asset = formats::open_valid_asset(o.asset);
  reader::ParallaxView view;
  formats::throw_if_failed(view.open(asset), o.asset);
  reader::ParallaxSample sample;
  reader::Status status;
  if (!texel.empty())
    status = view.depth(int64_t(texel[0]), int64_t(texel[1]), dir.data(), &sample);
  else
    status = view.footprint_depth({rect[0], rect[1], rect[2], rect[3]}, dir.data(), &sample);
  if (status.code() == reader::ErrorCode::InvalidArgument)
    throw CLI::ValidationError(texel.empty() ? "--rect" : "--texel", status.message());
  formats::throw_if_failed(status, o.asset);
  const double n = view.resolution();
  const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  const bool clamped = dir[2] / len < view.info().min_cos;
  if (o.json) {
    nlohmann::json out = {{"asset", o.asset},
                          {"query", "parallax"},
                          {"resolution", view.resolution()},
                          {"dirs", view.dirs()},
                          {"min_cos", view.info().min_cos},
                          {"reference_height", view.info().reference_height},
                          {"dir", vec(dir.data(), 3)},
                          {"direction_used", vec(sample.direction, 3)},
                          {"clamped_to_cap", clamped},
                          {"r", sample.r},
                          {"offset_tile", vec(sample.offset, 2)},
                          {"offset_texels", {sample.offset[0] * n, sample.offset[1] * n}}};
    if (!texel.empty())
      out["texel"] = {int64_t(texel[0]), int64_t(texel[1])};
    else
      out["rect"] = vec(rect.data(), 4);
    print_json(out);
    return 0;
  }
  if (!texel.empty())
    std::printf("parallax at texel (%lld, %lld)", static_cast<long long>(texel[0]),
                static_cast<long long>(texel[1]));
  else
    std::printf("parallax over [%g, %g) x [%g, %g) (mean)", rect[0], rect[2], rect[1], rect[3]);
  std::printf(", view (%.6g, %.6g, %.6g)%s\n", sample.direction[0], sample.direction[1],
              sample.direction[2], clamped ? " (clamped onto the parallax cap)" : "");
  std::printf("  r = %.9g tile-side units (hit %.9g below the reference plane z = %.9g)\n",
              sample.r, -sample.r, view.info().reference_height);
  std::printf("  offset (Eq. 2) = (%.9g, %.9g) tile = (%.6g, %.6g) texels\n", sample.offset[0],
              sample.offset[1], sample.offset[0] * n, sample.offset[1] * n);
  return 0;
}

int query_visibility(const QueryOptions& o) {
  if (o.dir.empty())
    throw CLI::ValidationError("--dir", "visibility queries need --dir x,y,z (light direction)");
  if (o.texel.empty()) throw CLI::ValidationError("--texel", "visibility queries need --texel i,j");
  const std::array<double, 3> dir = parse_direction(o.dir, "--dir");
  const std::vector<double> texel = parse_number_list(o.texel, "--texel", kTexel);
  const reader::Asset asset = formats::open_valid_asset(o.asset);
  reader::VisibilityAsgView view;
  formats::throw_if_failed(view.open(asset), o.asset);
  const int64_t x = int64_t(texel[0]), y = int64_t(texel[1]);
  double v = 0;
  reader::Status status = view.visibility(x, y, dir.data(), &v);
  if (status.code() == reader::ErrorCode::InvalidArgument)
    throw CLI::ValidationError("--dir", status.message());
  formats::throw_if_failed(status, o.asset);
  const model::AsgParams<double> p = view.lobe(x, y);
  const double error = view.fit_error(x, y);
  if (o.json) {
    nlohmann::json out = {
        {"asset", o.asset},
        {"query", "visibility"},
        {"resolution", view.resolution()},
        {"texel", {x, y}},
        {"dir", vec(dir.data(), 3)},
        {"visibility", v},
        {"asg",
         {{"axis", {p.axis.x, p.axis.y, p.axis.z}},
          {"rotation", p.rotation},
          {"lambda", p.lambda},
          {"mu", p.mu},
          {"amplitude", p.amplitude}}},
        {"fit_error", std::isfinite(error) ? nlohmann::json(error) : nlohmann::json(nullptr)}};
    print_json(out);
    return 0;
  }
  std::printf("visibility at texel (%lld, %lld), light (%.6g, %.6g, %.6g): V = %.6g\n",
              static_cast<long long>(x), static_cast<long long>(y), dir[0], dir[1], dir[2], v);
  std::printf(
      "  ASG: axis (%.6g, %.6g, %.6g), rotation %.6g rad, lambda %.6g, mu %.6g, "
      "amplitude %.6g\n",
      p.axis.x, p.axis.y, p.axis.z, p.rotation, p.lambda, p.mu, p.amplitude);
  if (std::isfinite(error)) std::printf("  fit RMS error over the sampled sky: %.6g\n", error);
  return 0;
}

int query_radiance(const QueryOptions& o) {
  if (o.lobe.empty())
    throw CLI::ValidationError("--lobe", "radiance queries need --lobe (e.g. specular_reflection)");
  if (o.h.empty()) throw CLI::ValidationError("--h", "radiance queries need --h x,y,z");
  if (o.rect.empty())
    throw CLI::ValidationError("--rect", "radiance queries need --rect x0,y0,x1,y1");
  RadianceQueryArgs args;
  args.lobe = o.lobe;
  args.cluster = o.cluster;
  args.h = parse_vec3(o.h, "--h");
  // A half vector of tiny or huge components (1e-310, 1e308) is the same direction scaled: divide
  // by the largest component so that its squared length neither underflows nor overflows.
  if (const double largest =
          std::max({std::fabs(args.h[0]), std::fabs(args.h[1]), std::fabs(args.h[2])});
      largest > 0 && (largest > 1e150 || largest < 1e-150))
    for (double& c : args.h)
      c /= largest;
  const std::vector<double> rect = parse_number_list(o.rect, "--rect", kRect);
  args.rect = {rect[0], rect[1], rect[2], rect[3]};
  args.source = o.tables;
  const reader::Asset asset = formats::open_valid_asset(o.asset);
  nlohmann::json answer = radiance_query(asset, args);
  if (o.json) {
    answer["asset"] = o.asset;
    answer["query"] = "radiance";
    print_json(answer);
  } else {
    std::fputs(radiance_query_text(answer).c_str(), stdout);
  }
  return 0;
}

// `query ASSET KIND`: one subcommand per kind, each with only the options that kind reads, so
// that an option of another kind is an unknown option (exit 1) naming it.
Action setup_query(CLI::App& app) {
  auto o = std::make_shared<QueryOptions>();
  add_asset_argument(app, o->asset);
  app.require_subcommand(1);
  const std::string dir_help = "direction x,y,z in the local frame (z = macro normal): ";
  auto* parallax = app.add_subcommand(
      "parallax", "the parallax depth r and its Eq. 2 offset at a texel or over a footprint");
  parallax->add_option("--dir", o->dir, dir_help + "the view direction (towards the viewer)");
  parallax->add_option("--texel", o->texel, "texel i,j (integers; the tile wraps)");
  parallax->add_option("--rect", o->rect,
                       "footprint x0,y0,x1,y1 in texel units, half-open, any size, wraps (the mean "
                       "over it)");
  add_json_flag(*parallax, o->json, "print the answer as JSON on stdout");
  auto* visibility =
      app.add_subcommand("visibility", "the visibility V of a texel for a light direction");
  visibility->add_option("--dir", o->dir, dir_help + "the light direction");
  visibility->add_option("--texel", o->texel, "texel i,j (integers; the tile wraps)");
  add_json_flag(*visibility, o->json, "print the answer as JSON on stdout");
  auto* radiance = app.add_subcommand(
      "radiance", "F_c(rect, h) of a lobe's Integral-Radiance table over a footprint");
  radiance->add_option("--lobe", o->lobe,
                       "lobe as in `clothbake bsdf` (specular_reflection, specular_transmission, "
                       "delta_transmission)");
  radiance->add_option("--cluster", o->cluster, "one visibility cluster (default: all)");
  radiance->add_option("--h", o->h, "half vector x,y,z in the local frame");
  radiance->add_option("--rect", o->rect,
                       "footprint x0,y0,x1,y1 in texel units, half-open, any size, wraps");
  add_tables_option(*radiance, o->tables);
  add_json_flag(*radiance, o->json, "print the answer as JSON on stdout");
  return [o, parallax, visibility] {
    if (parallax->parsed()) return query_parallax(*o);
    if (visibility->parsed()) return query_visibility(*o);
    return query_radiance(*o);
  };
}

const bool query_registered = register_command(
    {"query",
     "answer per-texel and footprint queries on an asset: query ASSET parallax|visibility|radiance "
     "(clothbake query ASSET KIND --help lists each one's options)",
     setup_query});

}  // namespace
}  // namespace clothbake::cli

// Bake plans from a scene (scene_plan.hpp).
#include "bake/reports/scene_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/fabric_load.hpp"
#include "bake/stages/stages.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "compress/map_entropy.hpp"
#include "formats/reader/parallax_hierarchy.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tables/half_vector_bins.hpp"

namespace clothbake::reports {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The parallax table's directions stop at this cosine (raycast/): views below it use its rim.
constexpr double kMinViewCos = 0.05;

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

// Estimates (docs/scene-plans.md, "Estimates"). Sizes after entropy coding, section by section
// (docs/format.md): exact where the size follows from the shapes (visibility, clusters, labels,
// the tables' per-texel maps and basis columns), the feature maps coded here as the bake codes
// them, and modelled where it depends on what the stages find:
//  - the parallax stream: kParallaxRateScale h^kParallaxRateExponent bytes per texel and stored
//    direction, h the coded height map's bytes per texel at its 256^2 equivalent (the relief's
//    detail, which the parallax codes follow), fitted by least squares in log-log to the six
//    example fabrics at their own resolutions (the satin's 0.013 at h = 0.091 to the argyle's
//    0.120 at 0.609; each within -40 % .. +35 %, the sheer voile lowest);
//  - the C-PCA: kCellsPerCluster cells per visibility cluster (clusters x yarns clusters when
//    split by yarn) of kRankAtReference images each beyond the mean at all bins of a 256^2 tile
//    whose narrowest roughness is kReferenceRoughness (the twill's 8.6), growing as
//    (kReferenceRoughness / sigma)^kRankRoughnessExponent (the satin's 26 at sigma 0.06), falling
//    as (kept bins / bins)^kRankBinExponent (the far swatch's 21 of 1024 bins: 2.8) and as (N /
//    256)^kRankResolutionExponent (the 64^2 test twill's 5.7), never above the kept bins; coded
//    coefficients at kBytesPerCoefficient (measured 0.10-0.34).
// Times: per-stage rates of the 256^2 twill (format 1.5, whose forms 2.0 kept), fitted to its full
// bake and its far-swatch plan (2 threads, idle machine; docs/scene-plans.md, "Estimates"): a
// fixed part per texel plus a part per texel and direction.
constexpr double kParallaxRateScale = 0.245, kParallaxRateExponent = 1.095;
// The twill at 64^2 against 256^2: its coded height map takes 4.9 times the bytes per texel
// (0.814 against 0.165), its parallax codes 1.19 times (0.0419 against 0.0352): the proxy h is
// taken at its 256^2 equivalent h (N / 256)^kHeightResolutionExponent, the rate scaled by
// (256 / N)^kParallaxResolutionExponent.
constexpr double kHeightResolutionExponent = 1.151, kParallaxResolutionExponent = 0.126;
// A coarser parallax error target e (planned_parallax_error) takes fewer bits a code: the stream
// scales as (e / e_fabric)^-kParallaxErrorExponent, fitted to the 256^2 twill's far-swatch plan
// (257 612 bytes at the fabric's 0.05 texels, 88 162 at 1 texel).
constexpr double kParallaxErrorExponent = 0.358;
constexpr double kCellsPerCluster = 0.75;
constexpr double kRankAtReference = 8.64, kReferenceRoughness = 0.4;
constexpr double kRankRoughnessExponent = 0.59, kRankBinExponent = 0.29;
constexpr double kRankResolutionExponent = 0.26;          // fewer texels, fewer distinct vectors
constexpr double kParallaxTableBytes = 2 * 23 * 256 * 2;  // u16 {groups, 23, 256}: 1-3 groups
constexpr double kBytesPerCoefficient = 0.25;
constexpr double kMetadataBytes = 10500, kPlanMetadataBytes = 3500;
constexpr double kParallaxPerTexel = 4.2e-6, kParallaxPerRay = 5.8e-8;
constexpr double kVisibilitySample = 4.8e-8;  // per texel and visibility direction
constexpr double kClusterPerTexel = 4.9e-6;
constexpr double kCompressPerTexel = 1.6e-5, kCompressPerTexelBin = 1.8e-8;
constexpr double kWritePerByte = 6.6e-9;

// Visibility directions: the ASG of a texel is fitted to binary visibility sampled on dirs^2 light
// directions, and every estimate reads it over a whole footprint. Where no footprint is narrower
// than kCoarseVisibilityFootprint texels (side), 12^2 directions give the same expected picture:
// the fits' sampling errors differ from texel to texel and average out over the footprint's
// tens of thousands of texels. Measured on the far swatch (docs/scene-plans.md, "Visibility
// directions"): the expected renders agree within the proof's standard error (3e-5 relMSE), at
// 4 % more noise per sample; 8^2 directions also pass the proof but cost 13 % more noise for
// 0.3 s less bake. `report plan` proves each plan against the full asset. Never more than the
// fabric asks for.
constexpr double kCoarseVisibilityFootprint = 128;  // texels, footprint side
constexpr int kCoarseVisibilityDirs = 12;           // per side, from that footprint up

int planned_visibility_dirs(int fabric_dirs, double footprint_min) {
  return footprint_min >= kCoarseVisibilityFootprint ? std::min(kCoarseVisibilityDirs, fabric_dirs)
                                                     : fabric_dirs;
}

// What the estimate needs of a bake: the kept view directions and half-vector bins, the gap
// kind, the visibility directions sampled, whether it is a plan.
struct EstimateShape {
  double view_dirs = 0, bins = 0;
  double parallax_error_ratio = 1;  // the planned parallax error over the fabric's
  bool gap_kind = false, planned = false;
  int visibility_dirs = 0;
};

// The feature maps as the bake stores them (coded): all of them and the height map alone, in
// bytes; 0 when they cannot be coded (the bake reports that error).
struct MapBytes {
  double all = 0, height = 0;
};

MapBytes feature_map_bytes(const Fabric& fabric) {
  try {
    MapBytes bytes;
    for (const formats::Section& section : compress::feature_map_sections(fabric.maps)) {
      bytes.all += double(section.bytes().size());
      if (section.type == reader::SectionType::HeightMap)
        bytes.height = double(section.bytes().size());
    }
    return bytes;
  } catch (const Error&) {
    return {};
  }
}

PlanEstimate estimate_bake(const Fabric& fabric, const EstimateShape& shape, const MapBytes& maps,
                           double narrowest_roughness) {
  const double n2 = double(fabric.maps.resolution) * fabric.maps.resolution;
  const double vis = double(shape.visibility_dirs) * shape.visibility_dirs;  // sampled
  // The clusters' grids keep the fabric's directions (cluster stage).
  const double cluster_vis = double(fabric.bake.visibility_dirs) * fabric.bake.visibility_dirs;
  std::vector<char> in_use(fabric.yarns.size(), 0);
  for (uint16_t id : fabric.maps.yarn_id)
    if (id < in_use.size()) in_use[id] = 1;
  const double yarns = std::max(1.0, double(std::count(in_use.begin(), in_use.end(), 1)));
  const double clusters =
      std::min(255.0, fabric.bake.clusters * (fabric.bake.clusters_by_yarn ? yarns : 1.0));
  const double m = fabric.bake.visibility_rank;
  const double all_bins = double(fabric.bake.radiance_dirs) * fabric.bake.radiance_dirs;
  const double rank = std::min(
      shape.bins, kRankAtReference *
                      std::pow(kReferenceRoughness / std::max(narrowest_roughness, 1e-3),
                               kRankRoughnessExponent) *
                      std::pow(std::min(1.0, shape.bins / all_bins), kRankBinExponent) *
                      std::pow(double(fabric.maps.resolution) / 256, kRankResolutionExponent));
  const double cells = std::max(1.0, std::round(kCellsPerCluster * clusters));
  const double images = cells * (1 + rank);
  const double scale = double(fabric.maps.resolution) / 256;
  const double height_256 =
      maps.height / std::max(n2, 1.0) * std::pow(scale, kHeightResolutionExponent);
  const double parallax_rate =
      kParallaxRateScale * std::pow(height_256, kParallaxRateExponent) *
      std::pow(1 / std::max(scale, 1e-3), kParallaxResolutionExponent) *
      std::pow(std::max(shape.parallax_error_ratio, 1.0), -kParallaxErrorExponent);
  const double fixed = 64 + 160.0 * double(fabric.yarns.size()) + maps.all  // records, maps
                       + 64 + n2 * 12                                       // visibility
                       + n2 + clusters * cluster_vis * 4                    // clusters
                       + clusters * (m + 1) * cluster_vis * 4 + n2 * m * 4  // basis
                       + kMetadataBytes + (shape.planned ? kPlanMetadataBytes : 0);
  const double all_dirs = double(fabric.bake.parallax_dirs) * fabric.bake.parallax_dirs;
  const double parallax =
      64 + all_dirs * (8 + 8 + 4) + kParallaxTableBytes + n2 * shape.view_dirs * parallax_rate;
  const double tables = 64 + 16 * cells + n2 + 4 * images + 2 * images * shape.bins +
                        n2 * rank * kBytesPerCoefficient +
                        (shape.gap_kind ? 64 + 16 + n2 + 4 + 2 + 2064 : 0);
  PlanEstimate e;
  e.planned_bytes = uint64_t(fixed + parallax + tables);
  e.planned_seconds = n2 * (kParallaxPerTexel + kParallaxPerRay * shape.view_dirs) +
                      n2 * vis * kVisibilitySample + n2 * kClusterPerTexel +
                      n2 * (kCompressPerTexel + kCompressPerTexelBin * shape.bins) +
                      double(e.planned_bytes) * kWritePerByte;
  return e;
}

}  // namespace

double planned_compression_target(double default_target, double budget) {
  // relMSE(planned, full) <= (e_planned + e_full)^2 (the two tables' relative RMS errors, at worst
  // adding up texel by texel); half the budget is kept for what else the plan changes.
  const double loosest = std::sqrt(budget / 2) - default_target;
  if (loosest >= default_target) return default_target;
  return std::max(loosest, default_target / 4);
}

double planned_parallax_error(double default_error, double budget, double footprint_min) {
  const double loosest = footprint_min * std::sqrt(budget / 16) / 4;
  return std::max(default_error, std::min(loosest, 1.0));
}

FabricPlan plan_fabric(const Fabric& fabric, const render::ObjectUsage& u, double max_error) {
  FabricPlan p;
  p.usage = u;
  // The stored parallax directions: those the views touch and the directions they are predicted
  // from in the hierarchical form (formats/reader/parallax_hierarchy.hpp); rays are cast for all.
  if (!p.usage.view_bins.empty())
    reader::close_under_parallax_references(p.usage.view_bins.data(),
                                            uint32_t(fabric.bake.parallax_dirs));
  p.resolution = fabric.maps.resolution;
  p.radiance_dirs = fabric.bake.radiance_dirs;
  p.half_vector_bins_total = p.radiance_dirs * p.radiance_dirs;
  p.fabric_visibility_dirs = p.visibility_dirs = fabric.bake.visibility_dirs;
  // Set before anything can return: the bake seeds its compression from the plan of any object
  // of the fabric, seen or not.
  const compress::CompressSettings defaults = compress::settings_from_bake(fabric.bake);
  p.compression_target =
      defaults.fixed ? 0.0 : planned_compression_target(defaults.max_error, max_error);
  if (u.pixels == 0) {
    p.warnings.push_back("no pixel sees this object: the scene needs nothing of its fabric");
    return p;
  }
  // Per-texel parallax: within one footprint the offsets differ by at most the largest offset
  // r_max = (height range) N tan(theta_view), so the footprint-averaged offset (the parallax
  // SAT) alone moves the footprint's edge by at most r_max texels: a relative error r_max / side.
  const auto [lo, hi] = std::minmax_element(fabric.maps.height.begin(), fabric.maps.height.end());
  const double range = fabric.maps.height.empty() ? 0.0 : double(*hi - *lo);
  const double c = std::max(u.min_view_cos, kMinViewCos);
  p.max_parallax_offset = range * p.resolution * std::sqrt(std::max(0.0, 1 - c * c)) / c;
  if (p.max_parallax_offset <= max_error * u.footprint_min)
    p.decisions.push_back(
        {"per-texel parallax", "left out",
         fmt("no footprint below %.3g texels and offsets of at most %.3g texels (%.3g %% of the "
             "smallest footprint, budget %.3g %%): the parallax SAT alone is kept",
             u.footprint_min, p.max_parallax_offset, 100 * p.max_parallax_offset / u.footprint_min,
             100 * max_error)});
  else
    p.decisions.push_back(
        {"per-texel parallax", "kept",
         fmt("footprints from %.3g texels and offsets up to %.3g texels (%.3g %% of the smallest "
             "footprint, above the budget %.3g %%)",
             u.footprint_min, p.max_parallax_offset, 100 * p.max_parallax_offset / u.footprint_min,
             100 * max_error)});
  // The parallax codes' precision: what the smallest footprint cannot see.
  p.parallax_max_error =
      planned_parallax_error(fabric.bake.parallax_max_error, max_error, u.footprint_min);
  if (p.parallax_max_error > fabric.bake.parallax_max_error)
    p.decisions.push_back(
        {"parallax precision", "coarser",
         fmt("RMS offset error %.3g texels instead of %.3g: footprints from %.3g texels see a "
             "relMSE of at most %.3g from it (a sixteenth of the budget or less)",
             p.parallax_max_error, fabric.bake.parallax_max_error, u.footprint_min,
             std::pow(4 * p.parallax_max_error / u.footprint_min, 2))});
  else
    p.decisions.push_back({"parallax precision", "kept",
                           fmt("RMS offset error %.3g texels: footprints from %.3g texels leave no "
                               "room for a coarser "
                               "one",
                               p.parallax_max_error, u.footprint_min)});
  // Transmission: only light on the side opposite to the viewer uses the transmission lobes, the
  // gap table and the delta lobe.
  if (!u.back_lit())
    p.decisions.push_back(
        {"transmission and gap tables", "left out",
         fmt("no light behind the cloth (%.0f lit pixel-light pairs, all on the viewer's side): "
             "specular and diffuse transmission, the delta lobe and the gap table left out",
             double(u.lit_same_side))});
  else
    p.decisions.push_back(
        {"transmission and gap tables", "kept",
         fmt("light reaches the side opposite to the viewer (%.0f of %.0f lit pixel-light pairs)",
             double(u.lit_opposite_side), double(u.lit_opposite_side + u.lit_same_side))});
  // Parallax view directions: those whose bilinear support some pixel's view touches.
  p.parallax_dirs = fabric.bake.parallax_dirs;
  const double views = double(p.usage.view_bins_used()),
               view_total = double(p.usage.view_bins.size());
  if (!p.usage.view_bins.empty() && views < view_total)
    p.decisions.push_back({"parallax view directions", "reduced",
                           fmt("views from cos %.3g up: %.0f of %.0f parallax directions kept, "
                               "%.0f of them for the views and the rest for predicting them (rays "
                               "cast for those only)",
                               u.min_view_cos, views, view_total, double(u.view_bins_used()))});
  else
    p.decisions.push_back({"parallax view directions", "kept",
                           fmt("the views reach all %.0f parallax directions", view_total)});
  // Half-vector bins: those whose bilinear support some lit (wi, wo) pair touches.
  const double used = double(u.half_vector_bins_used());
  const double angle = u.max_half_vector_angle * 180 / kPi;
  if (used < p.half_vector_bins_total)
    p.decisions.push_back({"half-vector bins", "reduced",
                           fmt("half vectors within %.3g deg of the normal: %.0f of %.0f bins kept",
                               angle, used, double(p.half_vector_bins_total))});
  else
    p.decisions.push_back(
        {"half-vector bins", "kept",
         fmt("half vectors up to %.3g deg from the normal reach all %.0f bins", angle, used)});
  // Sheen: strongest at grazing views and lights; its table is a few kilobytes, so it is always
  // kept and the reason says how much of the picture it matters for.
  if (u.grazing_view_fraction > 0 || u.min_light_cos < render::kGrazingCos)
    p.decisions.push_back({"sheen", "kept",
                           fmt("grazing views on %.3g %% of the pixels (smallest view cosine "
                               "%.3g), smallest light cosine %.3g",
                               100 * u.grazing_view_fraction, u.min_view_cos, u.min_light_cos)});
  else
    p.decisions.push_back(
        {"sheen", "kept",
         fmt("no grazing view or light (view cosines from %.3g, light cosines from %.3g): the "
             "sheen contributes little, kept for its size (one small table)",
             u.min_view_cos, u.min_light_cos)});
  // Visibility directions (planned_visibility_dirs above).
  p.fabric_visibility_dirs = fabric.bake.visibility_dirs;
  p.visibility_dirs = planned_visibility_dirs(p.fabric_visibility_dirs, u.footprint_min);
  if (p.visibility_dirs < p.fabric_visibility_dirs)
    p.decisions.push_back(
        {"visibility directions", "reduced",
         fmt("no footprint below %.3g texels: every estimate averages the ASGs of thousands of "
             "texels, so visibility is sampled on %.0f^2 instead of %.0f^2 light directions",
             u.footprint_min, p.visibility_dirs, p.fabric_visibility_dirs)});
  else
    p.decisions.push_back(
        {"visibility directions", "kept",
         fmt("footprints from %.3g texels (fewer directions from %.0f): %.0f^2 light directions",
             u.footprint_min, kCoarseVisibilityFootprint, p.visibility_dirs)});
  // Directional resolution: the 2-sigma rule on the narrowest roughness the fabric uses.
  double sigma = 1.0;
  std::vector<char> in_use(fabric.yarns.size(), 0);
  for (uint16_t id : fabric.maps.yarn_id)
    if (id < in_use.size()) in_use[id] = 1;
  for (std::size_t y = 0; y < fabric.yarns.size(); ++y)
    if (in_use[y]) sigma = std::min(sigma, fabric.yarns[y].roughness);
  const int needed = tables::bins_per_side_for_roughness(sigma);
  if (p.radiance_dirs >= needed)
    p.decisions.push_back({"radiance_dirs", "kept",
                           fmt("%.0f^2 bins resolve the narrowest roughness %.3g (2-sigma rule: "
                               "at least %.0f per side)",
                               p.radiance_dirs, sigma, needed)});
  else {
    p.decisions.push_back({"radiance_dirs", "kept",
                           fmt("%.0f^2 bins cannot resolve the narrowest roughness %.3g "
                               "(2-sigma rule: at least %.0f per side)",
                               p.radiance_dirs, sigma, needed)});
    p.warnings.push_back(
        fmt("[bake] radiance_dirs = %.0f cannot resolve roughness %.3g; "
            "radiance_dirs = %.0f would",
            p.radiance_dirs, sigma, needed));
  }
  // Estimates of the full bake and of this plan.
  {
    bool gaps = false;
    for (float g : fabric.maps.gap)
      gaps = gaps || g < 1.0f;
    const double dirs = double(fabric.bake.parallax_dirs) * fabric.bake.parallax_dirs;
    const double bins = double(p.half_vector_bins_total);
    const MapBytes maps = feature_map_bytes(fabric);
    const PlanEstimate full = estimate_bake(
        fabric, {dirs, bins, 1.0, gaps, false, p.fabric_visibility_dirs}, maps, sigma);
    const PlanEstimate planned = estimate_bake(
        fabric,
        {p.usage.view_bins.empty() ? dirs : double(std::max<uint64_t>(p.usage.view_bins_used(), 1)),
         double(std::max<uint64_t>(u.half_vector_bins_used(), 1)),
         fabric.bake.parallax_max_error > 0 ? p.parallax_max_error / fabric.bake.parallax_max_error
                                            : 1.0,
         gaps && u.back_lit(), true, p.visibility_dirs},
        maps, sigma);
    p.estimate = {full.planned_bytes, planned.planned_bytes, full.planned_seconds,
                  planned.planned_seconds};
  }
  {
    if (defaults.fixed)
      p.decisions.push_back(
          {"compression target", "kept",
           fmt("the fabric's fixed C-PCA shape (compress_rank = %.0f): the default bake's, on "
               "the kept bins",
               defaults.rank)});
    else {
      const double target = p.compression_target;
      p.decisions.push_back(
          {"compression target", target < defaults.max_error ? "tightened" : "kept",
           target < defaults.max_error
               ? fmt("the budget %.3g is below 8 e^2 for the default bake's target e = %.3g %%: "
                     "compressed tables at max_error = %.3g",
                     max_error, 100 * defaults.max_error, target)
               : fmt("the default bake's max_error = %.3g %%: the planned and full renders then "
                     "differ by at most (2 x %.3g %%)^2 = %.2g relMSE, within half of the "
                     "budget %.3g; a looser target would add noise, not change the picture",
                     100 * target, 100 * target, 4 * target * target, max_error)});
    }
  }
  return p;
}

ScenePlan plan_scene(const inputs::LoadedScene& loaded) {
  ScenePlan plan;
  plan.scene = loaded.scene.path;
  plan.max_error = loaded.scene.max_error;
  std::vector<Fabric> fabrics(loaded.scene.objects.size());
  std::vector<render::FabricShape> shapes(loaded.scene.objects.size());
  for (std::size_t k = 0; k < loaded.scene.objects.size(); ++k) {
    if (loaded.fabrics[k].empty()) continue;
    fabrics[k] = load_fabric(loaded.fabrics[k]);
    shapes[k] = {fabrics[k].maps.resolution, fabrics[k].bake.radiance_dirs,
                 fabrics[k].bake.parallax_dirs, fabrics[k].bake.parallax_min_cos};
  }
  const render::SceneUsage usage = render::analyse_usage(loaded.scene, shapes);
  for (std::size_t k = 0; k < loaded.scene.objects.size(); ++k) {
    if (loaded.fabrics[k].empty()) continue;
    FabricPlan p = plan_fabric(fabrics[k], usage.objects[k], plan.max_error);
    p.object = int(k);
    p.object_name = loaded.scene.objects[k].name;
    p.fabric_path = loaded.fabrics[k];
    plan.fabrics.push_back(std::move(p));
  }
  return plan;
}

nlohmann::json plan_json(const ScenePlan& plan) {
  nlohmann::json fabrics = nlohmann::json::array();
  for (const FabricPlan& p : plan.fabrics) {
    const render::ObjectUsage& u = p.usage;
    nlohmann::json decisions = nlohmann::json::array();
    for (const auto& d : p.decisions)
      decisions.push_back({{"item", d.item}, {"decision", d.decision}, {"reason", d.reason}});
    fabrics.push_back({{"object", p.object_name},
                       {"fabric", p.fabric_path},
                       {"resolution", p.resolution},
                       {"usage",
                        {{"pixels", u.pixels},
                         {"footprint_side_texels",
                          {{"min", u.footprint_min},
                           {"p05", u.footprint_p05},
                           {"median", u.footprint_median},
                           {"max", u.footprint_max}}},
                         {"min_view_cos", u.min_view_cos},
                         {"grazing_view_fraction", u.grazing_view_fraction},
                         {"views_front", u.views_front},
                         {"views_back", u.views_back},
                         {"lit_same_side", u.lit_same_side},
                         {"lit_opposite_side", u.lit_opposite_side},
                         {"min_light_cos", u.min_light_cos},
                         {"half_vector_bins_used", u.half_vector_bins_used()},
                         {"half_vector_bins_total", p.half_vector_bins_total},
                         {"view_bins_used", u.view_bins_used()},
                         {"view_bins_total", u.view_bins.size()},
                         {"max_half_vector_angle_deg", u.max_half_vector_angle * 180 / kPi},
                         {"max_parallax_offset_texels", p.max_parallax_offset}}},
                       {"decisions", decisions},
                       {"estimate",
                        {{"full_bytes", p.estimate.full_bytes},
                         {"planned_bytes", p.estimate.planned_bytes},
                         {"full_bake_seconds", p.estimate.full_seconds},
                         {"planned_bake_seconds", p.estimate.planned_seconds},
                         {"how",
                          "sizes after entropy coding: the section shapes, the feature maps "
                          "coded, the parallax codes and the C-PCA ranks modelled on the example "
                          "fabrics; times from per-stage rates measured on the 256^2 twill "
                          "(docs/scene-plans.md, \"Estimates\")"}}},
                       {"warnings", p.warnings}});
  }
  return {{"scene", plan.scene}, {"max_error", plan.max_error}, {"fabrics", fabrics}};
}

}  // namespace clothbake::reports

namespace clothbake::reports {
namespace {

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::equivalent(a, b, ec)) return true;
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}

uint32_t count_kept(const std::vector<uint8_t>& mask) {
  return uint32_t(std::count(mask.begin(), mask.end(), uint8_t(1)));
}

}  // namespace

ScenePlanSeeds seed_scene_plan(const std::string& scene_path, const std::string& fabric_path,
                               pipeline::BakeRequest* request) {
  return seed_scene_plan(inputs::load_scene(scene_path), scene_path, fabric_path, request);
}

ScenePlanSeeds seed_scene_plan(const inputs::LoadedScene& loaded, const std::string& scene_path,
                               const std::string& fabric_path, pipeline::BakeRequest* request) {
  const ScenePlan plan = plan_scene(loaded);
  std::vector<const FabricPlan*> mine;
  std::string used;
  for (const FabricPlan& p : plan.fabrics) {
    if (same_file(p.fabric_path, fabric_path))
      mine.push_back(&p);
    else if (used.find(p.fabric_path) == std::string::npos)
      used += (used.empty() ? "" : ", ") + p.fabric_path;
  }
  if (mine.empty())
    throw_input_error(scene_path + ": no object of the scene uses the fabric " + fabric_path +
                      (used.empty() ? std::string(" (no object names a fabric)")
                                    : " (the scene's fabrics: " + used + ")") +
                      "; nothing to plan, nothing written");
  // Merge the usages of every object with this fabric.
  stages::PlannedBake bake;
  ScenePlanSeeds out;
  uint64_t pixels = 0;
  bool back_lit = false;
  nlohmann::json objects = nlohmann::json::array();
  const nlohmann::json all = plan_json(plan);
  int visibility_dirs = 0;    // the most any object of this fabric that some pixel sees needs
  double parallax_error = 0;  // the tightest any object of this fabric that some pixel sees needs
  for (const FabricPlan* p : mine) {
    if (p->usage.pixels > 0) visibility_dirs = std::max(visibility_dirs, p->visibility_dirs);
    if (p->usage.pixels > 0 && p->parallax_max_error > 0)
      parallax_error = parallax_error > 0 ? std::min(parallax_error, p->parallax_max_error)
                                          : p->parallax_max_error;
    out.visibility_dirs_total = p->fabric_visibility_dirs;
    pixels += p->usage.pixels;
    back_lit = back_lit || p->usage.back_lit();
    auto merge = [](std::vector<uint8_t>& into, const std::vector<uint8_t>& from) {
      if (into.empty()) into.assign(from.size(), 0);
      for (std::size_t b = 0; b < from.size() && b < into.size(); ++b)
        into[b] |= from[b];
    };
    merge(bake.half_vector_bins, p->usage.half_vector_bins);
    merge(bake.view_bins, p->usage.view_bins);
    for (const auto& f : all["fabrics"])
      if (f["object"] == p->object_name && f["fabric"] == p->fabric_path) objects.push_back(f);
  }
  const std::string names = mine.front()->object_name.empty()
                                ? "object " + std::to_string(mine.front()->object)
                                : "'" + mine.front()->object_name + "'";
  if (pixels == 0)
    throw_input_error(scene_path + ": the plan for " + fabric_path +
                      " leaves out everything: no pixel sees " + names +
                      " (nothing to bake, nothing written)");
  out.half_vector_bins_total = uint32_t(bake.half_vector_bins.size());
  out.view_bins_total = uint32_t(bake.view_bins.size());
  out.half_vector_bins_kept = count_kept(bake.half_vector_bins);
  out.view_bins_kept = count_kept(bake.view_bins);
  if (out.half_vector_bins_kept == 0)
    throw_input_error(scene_path + ": the plan for " + fabric_path +
                      " leaves out everything: no light reaches " + names +
                      " (every half-vector bin would be left out; nothing written)");
  // Every bin kept: no map (the sections stay in their full form).
  if (out.half_vector_bins_kept == out.half_vector_bins_total) bake.half_vector_bins.clear();
  if (out.view_bins_kept == out.view_bins_total) bake.view_bins.clear();
  bake.transmission = back_lit;
  out.transmission = back_lit;
  if (!back_lit) out.left_out.push_back("transmission and gap tables (no light behind the cloth)");
  if (!bake.half_vector_bins.empty())
    out.left_out.push_back(std::to_string(out.half_vector_bins_total - out.half_vector_bins_kept) +
                           " of " + std::to_string(out.half_vector_bins_total) +
                           " half-vector bins");
  if (!bake.view_bins.empty())
    out.left_out.push_back(std::to_string(out.view_bins_total - out.view_bins_kept) + " of " +
                           std::to_string(out.view_bins_total) + " parallax view directions");
  if (visibility_dirs == 0) visibility_dirs = out.visibility_dirs_total;  // no pixel: refused below
  out.visibility_dirs = visibility_dirs;
  bake.parallax_max_error = parallax_error;
  if (visibility_dirs < out.visibility_dirs_total) {
    bake.visibility_dirs = visibility_dirs;
    const int total = out.visibility_dirs_total * out.visibility_dirs_total;
    out.left_out.push_back(std::to_string(total - visibility_dirs * visibility_dirs) + " of " +
                           std::to_string(total) + " visibility light directions (sampled on " +
                           std::to_string(visibility_dirs) + "^2 instead of " +
                           std::to_string(out.visibility_dirs_total) + "^2)");
  }

  // The sections that record the plan.
  std::vector<formats::Section> sections;
  auto map_section = [&](uint32_t instance, const std::vector<uint8_t>& mask) {
    const uint32_t n = uint32_t(std::lround(std::sqrt(double(mask.size()))));
    sections.push_back(
        formats::make_array_section<uint8_t>(reader::SectionType::BinMap, instance, mask, {n, n}));
  };
  if (!bake.half_vector_bins.empty()) map_section(reader::kHalfVectorBinMap, bake.half_vector_bins);
  if (!bake.view_bins.empty()) map_section(reader::kViewBinMap, bake.view_bins);
  const std::string scene_bytes = inputs::read_file_bytes(scene_path, "scene");
  out.scene_hash = inputs::xxh64_hex(scene_bytes);
  reader::ScenePlanRecord record{};
  record.flags = back_lit ? 0u : reader::kPlanNoTransmission;
  record.half_vector_bins_kept = out.half_vector_bins_kept;
  record.view_bins_kept = out.view_bins_kept;
  record.scene_hash = std::stoull(out.scene_hash, nullptr, 16);
  record.max_error = plan.max_error;
  sections.push_back(formats::make_record_section<reader::ScenePlanRecord>(
      reader::SectionType::ScenePlan, 0, std::span<const reader::ScenePlanRecord>(&record, 1)));

  out.metadata = {{"scene", scene_path},
                  {"scene_xxh64", out.scene_hash},
                  {"max_error", plan.max_error},
                  {"left_out", out.left_out},
                  {"half_vector_bins_kept", out.half_vector_bins_kept},
                  {"half_vector_bins_total", out.half_vector_bins_total},
                  {"view_bins_kept", out.view_bins_kept},
                  {"view_bins_total", out.view_bins_total},
                  {"visibility_dirs", out.visibility_dirs},
                  {"visibility_dirs_total", out.visibility_dirs_total},
                  {"parallax_max_error", parallax_error},
                  {"transmission", back_lit},
                  {"objects", objects}};
  // The planned tables' target (planned_compression_target; unless the command line set one, or
  // the fabric asks for a fixed C-PCA shape, which the plan keeps): never tighter than the
  // default bake's unless the budget needs it (only then can the tables cost more than the
  // default bake's).
  const FabricPlan& first = *mine.front();
  if (!request->seeds.contains(stages::kCompressSettingsArtifact) && first.compression_target > 0) {
    compress::CompressRequest compression;
    compression.max_error = first.compression_target;
    request->seeds.put(stages::kCompressSettingsArtifact, compression);
    out.metadata["compression_target"] = *compression.max_error;
  }
  request->seeds.put(stages::kScenePlanArtifact, std::move(bake));
  request->seeds.put("section/scene_plan", std::move(sections));
  request->seeds.put("metadata/scene_plan", out.metadata);
  return out;
}

}  // namespace clothbake::reports

#include "bake/inputs/fabric_load.hpp"
#include "bake/inputs/map_limits.hpp"
#include "model/parameter_ranges.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "bake/inputs/fabric_files.hpp"
#include "bake/inputs/fabric_toml.hpp"
#include "bake/inputs/input_kind.hpp"
#include "bake/inputs/map_image.hpp"
#include "bake/inputs/map_normals.hpp"
#include "bake/inputs/weave.hpp"
#include "bake/inputs/wif.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "tables/half_vector_bins.hpp"

namespace clothbake {

static_assert(kMaxResolution == inputs::kMaxMapSide, "one limit for maps and bakes");

const char* fabric_source_name(FabricSource source) {
  switch (source) {
    case FabricSource::Images:
      return "images";
    case FabricSource::NamedWeave:
      return "named_weave";
    case FabricSource::MatrixWeave:
      return "matrix_weave";
    case FabricSource::Wif:
      return "wif";
  }
  return "unknown";
}

namespace {

using inputs::Range;
using inputs::TomlSection;

// Valid ranges, shared with docs/fabric-format.md (keep them in sync).
const Range kRoughness{model::kMinRoughness, model::kMaxRoughness};  // model/parameter_ranges.hpp
const Range kOpticalThickness{0.0, 1000.0, true, false};             // (0, 1000]
const Range kUnitInterval{0.0, 1.0};                                 // [0, 1]
const Range kPositiveLength{0.0, 1e6, true, false};                  // (0, 1e6]
const Range kPositiveScale{0.0, 1e12, true, false};                  // (0, 1e12]
const Range kSpacing{0.0, 1000.0, true, false};                      // (0, 1000] mm
const Range kWidthFraction{0.0, 1.0, true, false};                   // (0, 1]
const Range kTwist{-90.0, 90.0, true, true};                         // (-90, 90) degrees
const Range kMinCos{0.0, 0.95};                                      // [0, 0.95]

// "tile" (no physical size) and the physical units.
const std::vector<std::string> kLengthUnits = [] {
  std::vector<std::string> units = {"tile"};
  units.insert(units.end(), inputs::kPhysicalLengthUnits.begin(),
               inputs::kPhysicalLengthUnits.end());
  return units;
}();

YarnMaterial parse_yarn(const TomlSection& s, const std::string& default_name) {
  s.check_keys({"name", "roughness", "optical_thickness", "specular_albedo", "diffuse_reflectance",
                "diffuse_transmittance", "color"});
  YarnMaterial y;
  y.name = s.string("name").value_or(default_name);
  if (y.name.empty()) s.fail("name", "must not be empty");
  y.roughness = s.real("roughness", kRoughness).value_or(y.roughness);
  y.optical_thickness =
      s.real("optical_thickness", kOpticalThickness).value_or(y.optical_thickness);
  y.specular_albedo = s.rgb("specular_albedo", kUnitInterval).value_or(y.specular_albedo);
  y.diffuse_reflectance =
      s.rgb("diffuse_reflectance", kUnitInterval).value_or(y.diffuse_reflectance);
  y.diffuse_transmittance =
      s.rgb("diffuse_transmittance", kUnitInterval).value_or(y.diffuse_transmittance);
  y.color = s.rgb("color", kUnitInterval).value_or(y.color);
  // Reflection and transmission of the higher-order (diffuse) lobes share the energy that entered.
  for (int c = 0; c < 3; ++c)
    if (y.diffuse_reflectance[c] + y.diffuse_transmittance[c] > 1.0 + 1e-9)
      s.fail("diffuse_transmittance",
             fmt::format("[{}] = {} plus diffuse_reflectance[{}] = {} exceeds 1 (energy is not "
                         "conserved)",
                         c, y.diffuse_transmittance[c], c, y.diffuse_reflectance[c]));
  // alpha + R_d + T_d <= 1 per channel guarantees that the BSDF conserves energy (docs/model.md);
  // it is sufficient, not necessary (the specular lobes reflect less than alpha), hence a warning,
  // not an error.
  for (int c = 0; c < 3; ++c) {
    const double sum = y.specular_albedo[c] + y.diffuse_reflectance[c] + y.diffuse_transmittance[c];
    if (sum > 1.0 + 1e-9) {
      warn(
          fmt::format("{}: {} [{}] + diffuse_reflectance + diffuse_transmittance = {:.6g} exceeds "
                      "1: the BSDF may not conserve energy (lower one of them)",
                      s.where("specular_albedo"), s.dotted("specular_albedo"), c, sum));
      break;
    }
  }
  return y;
}

SheenParams parse_sheen(const TomlSection& s) {
  s.check_keys({"color", "roughness"});
  SheenParams p;
  p.color = s.rgb("color", kUnitInterval).value_or(p.color);
  p.roughness = s.real("roughness", kRoughness).value_or(p.roughness);
  return p;
}

BakeSettings parse_bake(const TomlSection& s) {
  s.check_keys({"resolution", "parallax_dirs", "parallax_min_cos", "parallax_max_error",
                "visibility_dirs", "radiance_dirs", "clusters", "clusters_by_yarn",
                "visibility_rank", "compress", "compress_clusters", "compress_rank", "seed"});
  BakeSettings b;
  b.resolution =
      int(s.integer("resolution", kMinResolution, kMaxResolution).value_or(b.resolution));
  b.parallax_dirs = int(s.integer("parallax_dirs", 2, 256).value_or(b.parallax_dirs));
  b.parallax_min_cos = s.real("parallax_min_cos", kMinCos).value_or(b.parallax_min_cos);
  // (0, 1] texels (docs/compression.md, "Compressed parallax").
  b.parallax_max_error =
      s.real("parallax_max_error", Range{0, 1, true, false}).value_or(b.parallax_max_error);
  b.visibility_dirs = int(s.integer("visibility_dirs", 2, 256).value_or(b.visibility_dirs));
  // 0 (or no key) means "auto": chosen from the narrowest yarn roughness once the yarns are known
  // (tables::default_bins_per_side).
  b.radiance_dirs = int(s.integer("radiance_dirs", 0, 256).value_or(0));
  if (b.radiance_dirs == 1)
    throw_input_error(s.where("radiance_dirs") +
                      "radiance_dirs = 1 is out of range; valid: 0 (auto) or [2, 256]");
  b.clusters = int(s.integer("clusters", 1, 64).value_or(b.clusters));
  b.clusters_by_yarn = s.boolean("clusters_by_yarn").value_or(b.clusters_by_yarn);
  b.visibility_rank = int(s.integer("visibility_rank", 0, 16).value_or(b.visibility_rank));
  b.compress = s.boolean("compress").value_or(b.compress);
  // 0 means "auto" (the compress stage's target-error mode); the upper bounds are the C-PCA's
  // (compress/compress_settings.hpp: kMaxCpcaClustersPerStratum, kMaxCpcaRank).
  b.compress_clusters = int(s.integer("compress_clusters", 0, 64).value_or(b.compress_clusters));
  b.compress_rank = int(s.integer("compress_rank", 0, 255).value_or(b.compress_rank));
  b.seed = uint64_t(s.integer("seed", 0, INT64_MAX).value_or(int64_t(b.seed)));
  return b;
}

weave::YarnGeometry parse_geometry(const TomlSection& s, weave::YarnGeometry g,
                                   weave::YarnGeometry* overrides_mask = nullptr) {
  s.check_keys({"spacing_mm", "width", "height_mm", "twist_deg"});
  // overrides_mask, when given, receives NaN for fields the file does not set.
  auto set = [&](const char* key, const Range& range, double& field, double& mask) {
    auto v = s.real(key, range);
    if (v) field = *v;
    mask = v ? *v : std::nan("");
  };
  weave::YarnGeometry mask;
  set("spacing_mm", kSpacing, g.spacing_mm, mask.spacing_mm);
  set("width", kWidthFraction, g.width, mask.width);
  set("height_mm", kSpacing, g.height_mm, mask.height_mm);
  set("twist_deg", kTwist, g.twist_deg, mask.twist_deg);
  if (overrides_mask) *overrides_mask = mask;
  return g;
}

// Applies the fields of `mask` that are not NaN to `g`.
void apply_overrides(weave::YarnGeometry& g, const weave::YarnGeometry& mask) {
  if (!std::isnan(mask.spacing_mm)) g.spacing_mm = mask.spacing_mm;
  if (!std::isnan(mask.width)) g.width = mask.width;
  if (!std::isnan(mask.height_mm)) g.height_mm = mask.height_mm;
  if (!std::isnan(mask.twist_deg)) g.twist_deg = mask.twist_deg;
}

// radiance_dirs = 0 ("auto", the default): the bins that resolve the narrowest yarn roughness for
// the multi-scale control variate (tables::default_bins_per_side; docs/fabric-format.md).
void resolve_radiance_dirs(BakeSettings& b, const std::vector<double>& roughness) {
  if (b.radiance_dirs != 0) return;
  double narrowest = YarnMaterial{}.roughness;
  if (!roughness.empty()) narrowest = *std::min_element(roughness.begin(), roughness.end());
  b.radiance_dirs = tables::default_bins_per_side(narrowest);
}

void resolve_radiance_dirs(Fabric& f) {
  std::vector<double> roughness;
  for (const YarnMaterial& y : f.yarns)
    roughness.push_back(y.roughness);
  resolve_radiance_dirs(f.bake, roughness);
}

// What a file given as a fabric holds: a WIF draft by its name (".wif", any case) or by its [WIF]
// section, else what its bytes say (input_kind.hpp).
inputs::InputKind fabric_input_kind(const std::string& path, std::string_view bytes) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".wif" ? inputs::InputKind::Wif : inputs::sniff_input_kind(bytes);
}

std::vector<YarnMaterial> default_weave_yarns() {
  std::vector<YarnMaterial> yarns(2);
  yarns[0].name = "warp";
  yarns[1].name = "weft";
  return yarns;
}

// Rethrows an Error from another component with our context in front.
template <class F>
auto with_context(const std::string& context, F&& f) {
  try {
    return f();
  } catch (const Error& e) {
    throw Error(e.code(), fmt::format("{}: {}", context, e.what()));
  }
}

// Generates the maps of a weave fabric and fills the bookkeeping fields.
void build_weave_maps(LoadedFabric& out, weave::WeaveSpec spec, const std::string& where) {
  Fabric& f = out.fabric;
  if (f.yarns.size() < 2)
    throw_input_error(fmt::format(
        "{}: the weave uses yarn ids 0 (warp) and 1 (weft) but only {} [[yarn]] {} declared; "
        "declare one [[yarn]] for the warp and one for the weft, in that order",
        where, f.yarns.size(), f.yarns.size() == 1 ? "is" : "are"));
  // Threads without a colour of their own take their system's yarn colour.
  if (spec.end_colors.empty())
    spec.end_colors.assign(std::size_t(spec.matrix.ends), f.yarns[0].color);
  if (spec.pick_colors.empty())
    spec.pick_colors.assign(std::size_t(spec.matrix.picks), f.yarns[1].color);
  weave::validate_weave_spec(spec, where);
  f.maps = weave::generate_weave_maps(spec, f.bake.resolution, where);
  // Extreme thread geometry (spacing_mm = 1e-300, a tile of 1e-30 mm) overflows the maps or gives
  // reliefs no ray can trace: refuse it here, naming the keys, not later in a stage.
  const std::string keys =
      "the thread geometry ([weave.warp] / [weave.weft] spacing_mm, width, "
      "height_mm)";
  inputs::check_maps_finite(f.maps, where, keys);
  inputs::check_heights(f.maps.height, f.maps.resolution, where, keys);
  const weave::TileSize tile = weave::weave_tile_size(spec);
  f.tile_size_mm = tile.width_mm;
  // The maps are a square tile: a repeat of W x H mm with H / W far from 1 is stretched back by the
  // renderer, and its slopes along v are off by that factor (docs/weaves.md, "Non-square
  // repeats"). Say so, with the whole number of repeats along each side that comes nearest square.
  const double aspect = tile.height_mm / tile.width_mm;
  if (std::isfinite(aspect) && (aspect > 1.25 || aspect < 0.8)) {
    int best_ends = 1, best_picks = 1;
    double best = std::abs(std::log(aspect));
    for (int e = 1; e <= 8; ++e)
      for (int p = 1; p <= 8; ++p)
        if (const double r = std::abs(std::log(aspect * p / e)); r < best - 1e-12) {
          best = r;
          best_ends = e;
          best_picks = p;
        }
    warn(
        fmt::format("{}: the repeat is {:.4g} x {:.4g} mm (H/W {:.3g}) but the maps are a square "
                    "tile: slopes along the weft direction are off by a factor {:.3g}; in a fabric "
                    "description, [weave] "
                    "repeat = [{}, {}] makes the tile {} x {} repeats (H/W {:.3g})",
                    where, tile.width_mm, tile.height_mm, aspect, aspect, best_ends, best_picks,
                    best_ends, best_picks, aspect * best_picks / best_ends));
  }
  for (std::size_t i = 2; i < f.yarns.size(); ++i)
    warn(
        fmt::format("{}: yarn[{}] '{}' is declared but a weave only uses yarns 0 (warp) and 1 "
                    "(weft)",
                    where, i, f.yarns[i].name));
  out.weave = std::move(spec);
}

// Checks cross-map consistency of image maps: yarn ids index declared yarns.
void check_yarn_ids(const Fabric& f, const std::string& context) {
  const FabricMaps& m = f.maps;
  std::vector<bool> used(f.yarns.size(), false);
  for (int y = 0; y < m.resolution; ++y)
    for (int x = 0; x < m.resolution; ++x) {
      uint16_t id = m.yarn_id[m.index(x, y)];
      if (id >= f.yarns.size())
        throw_input_error(fmt::format(
            "{}: pixel ({}, {}) has yarn id {} but only {} yarn{} declared (ids 0..{}); add "
            "[[yarn]] entries or fix the map",
            context, x, y, id, f.yarns.size(), f.yarns.size() == 1 ? " is" : "s are",
            f.yarns.size() - 1));
      used[id] = true;
    }
  for (std::size_t i = 0; i < used.size(); ++i)
    if (!used[i])
      warn(fmt::format("{}: yarn[{}] '{}' is declared but no texel uses it", context, i,
                       f.yarns[i].name));
}

void warn_if_flat(const Fabric& f, const std::string& context) {
  const auto& h = f.maps.height;
  auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  if (lo != h.end() && *lo == *hi)
    warn(
        fmt::format("{}: the height map is constant (h = {}); the fabric is flat, so parallax "
                    "and self-shadowing will have no effect",
                    context, *lo));
}

struct MapsSection {
  std::string height, tangent, normal, gap, yarn_id, albedo;  // as written in the file
};

void load_image_maps(LoadedFabric& out, const TomlSection& maps,
                     const std::optional<TomlSection>& tile, const std::string& toml_path,
                     const std::string& base_dir, std::optional<int64_t> bake_resolution) {
  Fabric& f = out.fabric;
  maps.check_keys({"height", "height_scale", "height_units", "tangent", "normal", "gap", "yarn_id",
                   "albedo", "albedo_encoding"});

  // Units: the tile's physical size and the unit of stored heights.
  std::string tile_units = "tile";
  double tile_size = 1.0;
  if (tile) {
    tile->check_keys({"size", "units"});
    tile_units = tile->choice("units", kLengthUnits).value_or("tile");
    auto size = tile->real("size", kPositiveLength);
    if (tile_units == "tile" && size)
      tile->fail("size",
                 "has no meaning with units = \"tile\" (the tile side is the unit); set "
                 "units to \"um\", \"mm\", \"cm\", \"m\" or \"in\"");
    if (tile_units != "tile" && !size)
      tile->fail("size", fmt::format("is required when units = \"{}\" (the tile's side length)",
                                     tile_units));
    if (size) tile_size = *size;
  }
  f.tile_size_mm = tile_units == "tile" ? 0.0 : tile_size * inputs::length_unit_in_mm(tile_units);
  std::string height_units = maps.choice("height_units", kLengthUnits).value_or(tile_units);
  if (height_units != "tile" && tile_units == "tile")
    maps.fail("height_units",
              fmt::format("= \"{}\" needs the tile's physical size: set [tile] size and units",
                          height_units));
  double height_scale = maps.real("height_scale", kPositiveScale).value_or(1.0);
  double to_tile_units =
      height_units == "tile" ? 1.0 : inputs::length_unit_in_mm(height_units) / f.tile_size_mm;
  bool srgb = maps.choice("albedo_encoding", {"linear", "srgb"}).value_or("linear") == "srgb";

  struct Entry {
    const char* role;
    bool required;
  };
  const Entry entries[] = {{"height", true}, {"tangent", true},  {"normal", false},
                           {"gap", false},   {"yarn_id", false}, {"albedo", false}};
  // Every key is checked before any image is read, so that a missing key is reported first.
  for (const auto& e : entries) {
    auto file = maps.string(e.role);
    if (!file && e.required)
      maps.fail(e.role, fmt::format("is missing: an image-based fabric needs a {} map ([maps] "
                                    "{} = \"file.exr\")",
                                    e.role, e.role));
    if (file && file->empty()) maps.fail(e.role, "must name an image file, got an empty string");
  }
  std::vector<inputs::MapImage> images;
  for (const auto& e : entries) {
    auto file = maps.string(e.role);
    if (!file) continue;
    std::string path = inputs::resolve_relative(base_dir, *file);
    std::string key_context = fmt::format("{}: maps.{}", maps.where(e.role), e.role);
    inputs::MapImage image = inputs::read_map_image(path, e.role, key_context);
    const std::string& context = image.context;
    if (!images.empty() && image.image.width != images.front().image.width)
      throw_input_error(fmt::format(
          "{}: image is {}x{} but maps.{} is {}x{}; all maps of a fabric must have the same size",
          context, image.image.width, image.image.height, images.front().role,
          images.front().image.width, images.front().image.height));
    f.inputs.push_back({e.role, path, inputs::hash_file(path, key_context)});
    images.push_back(std::move(image));
  }

  const int n = images.front().image.width;
  if (n < kMinResolution || n > kMaxResolution)
    throw_input_error(fmt::format("{}: image is {}x{}; map resolution must be in [{}, {}]",
                                  images.front().context, n, n, kMinResolution, kMaxResolution));
  if (bake_resolution && *bake_resolution != n)
    throw_input_error(fmt::format(
        "{}: bake.resolution = {} but the maps are {}x{}; maps are not resampled: resize them or "
        "set bake.resolution = {}",
        toml_path, *bake_resolution, n, n, n));
  f.bake.resolution = n;

  FabricMaps& m = f.maps;
  m.resolution = n;
  const std::size_t texels = std::size_t(n) * n;
  const inputs::MapImage* albedo_image = nullptr;
  for (const auto& image : images) {
    if (image.role == "height") {
      // An integer image's values are fractions of its full range: in tile units, unscaled, that
      // is a relief up to a whole tile side tall (a woven relief is a few percent of it). Legal,
      // and sometimes meant, so a warning, not an error.
      if (image.integer_encoded && height_units == "tile" && !maps.has("height_scale"))
        warn(
            fmt::format("{}: a {}-bit height image in tile units without height_scale: its "
                        "values 0..1 are a relief up to a whole tile side tall; give [maps] "
                        "height_scale (the relief's height in tile sides) or the tile's size "
                        "and height_units = \"mm\"",
                        image.context, image.bits));
      m.height = inputs::decode_height(image, height_scale * to_tile_units);
      inputs::check_heights(m.height, n, image.context,
                            "[maps] height_scale, height_units and the image's values");
    }
    if (image.role == "tangent") m.tangent = inputs::decode_tangents(image);
    if (image.role == "normal") m.normal = inputs::decode_normals(image);
    if (image.role == "gap") m.gap = inputs::decode_gap(image);
    if (image.role == "yarn_id") m.yarn_id = inputs::decode_yarn_ids(image);
    if (image.role == "albedo") albedo_image = &image;
  }
  if (m.normal.empty()) m.normal = inputs::normals_from_height(m.height, n);
  if (m.gap.empty()) m.gap.assign(texels, 1.0f);
  if (m.yarn_id.empty()) m.yarn_id.assign(texels, 0);

  if (f.yarns.empty()) {
    f.yarns.resize(1);
    f.yarns[0].name = "yarn";
  }
  std::string yarn_context = toml_path;
  for (const auto& image : images)
    if (image.role == "yarn_id") yarn_context = image.context;
  check_yarn_ids(f, yarn_context);

  if (albedo_image) {
    m.albedo = inputs::decode_albedo(*albedo_image, srgb);
  } else {
    m.albedo.resize(texels);
    for (std::size_t i = 0; i < texels; ++i) {
      const Rgb& c = f.yarns[m.yarn_id[i]].color;
      m.albedo[i] = Vec3f{float(c[0]), float(c[1]), float(c[2])};
    }
  }
  warn_if_flat(f, images.front().context);
}

void load_weave(LoadedFabric& out, const TomlSection& w, const std::string& base_dir,
                const std::string& toml_path) {
  Fabric& f = out.fabric;
  w.check_keys({"name", "matrix", "wif", "warp", "weft", "end_colors", "pick_colors", "repeat"});
  int sources = int(w.has("name")) + int(w.has("matrix")) + int(w.has("wif"));
  if (sources != 1)
    throw_input_error(fmt::format(
        "{}: [weave] needs exactly one of name = \"twill2/1\", matrix = [\"0101\", ...] or wif = "
        "\"draft.wif\"; {}",
        w.where(""), sources == 0 ? "none is given" : "several are given"));

  weave::WeaveSpec spec;
  // Nothing overridden unless [weave.warp] / [weave.weft] state it (NaN: not set). Default-made
  // masks used to replace a draft's spacings with the defaults when a section was absent.
  const double unset = std::nan("");
  weave::YarnGeometry warp_mask{unset, unset, unset, unset}, weft_mask = warp_mask;
  auto warp_section = w.table("warp");
  auto weft_section = w.table("weft");
  if (warp_section) spec.warp = parse_geometry(*warp_section, spec.warp, &warp_mask);
  if (weft_section) spec.weft = parse_geometry(*weft_section, spec.weft, &weft_mask);

  if (auto name = w.string("name")) {
    std::string where = w.where("name") + ": weave.name";
    spec.matrix = with_context(where, [&] { return weave::named_weave(*name); });
    out.source = FabricSource::NamedWeave;
    out.weave_label = *name;
  } else if (auto rows = w.string_array("matrix")) {
    std::string where = w.where("matrix") + ": weave.matrix";
    spec.matrix = weave::matrix_from_rows(*rows, where);
    weave::check_weavable(spec.matrix, where);
    out.source = FabricSource::MatrixWeave;
    out.weave_label = "matrix";
  } else {
    auto file = w.string("wif");
    if (file->empty()) w.fail("wif", "must name a WIF file, got an empty string");
    std::string path = inputs::resolve_relative(base_dir, *file);
    std::string where = fmt::format("{}: weave.wif (\"{}\")", w.where("wif"), path);
    WifDraft draft = with_context(where, [&] { return read_wif(path); });
    f.inputs.push_back({"wif", path, inputs::hash_file(path, where)});
    // The draft's geometry, with what the fabric file states on top (explicit settings win, for
    // every thread: a WIF has no yarn width or twist).
    spec = std::move(draft.spec);
    apply_overrides(spec.warp, warp_mask);
    apply_overrides(spec.weft, weft_mask);
    for (auto& g : spec.end_geometry)
      apply_overrides(g, warp_mask);
    for (auto& g : spec.pick_geometry)
      apply_overrides(g, weft_mask);
    out.source = FabricSource::Wif;
    out.weave_label =
        draft.title.empty() ? std::filesystem::path(path).filename().string() : draft.title;
  }

  if (auto colors = w.rgb_list("end_colors", kUnitInterval)) {
    if (int(colors->size()) != spec.matrix.ends)
      w.fail("end_colors", fmt::format("has {} colours but the weave has {} ends (warp threads)",
                                       colors->size(), spec.matrix.ends));
    spec.end_colors = *colors;
  }
  if (auto colors = w.rgb_list("pick_colors", kUnitInterval)) {
    if (int(colors->size()) != spec.matrix.picks)
      w.fail("pick_colors", fmt::format("has {} colours but the weave has {} picks (weft threads)",
                                        colors->size(), spec.matrix.picks));
    spec.pick_colors = *colors;
  }
  // A tile of several repeats (docs/weaves.md, "Non-square repeats"): [ends_times, picks_times].
  if (const auto times = w.numbers("repeat", 2, Range{1, 16})) {
    if ((*times)[0] != std::floor((*times)[0]) || (*times)[1] != std::floor((*times)[1]))
      w.fail("repeat", "must be [ends_times, picks_times]: two whole numbers in [1, 16]");
    spec = weave::repeat_weave_spec(spec, int((*times)[0]), int((*times)[1]),
                                    w.where("repeat") + ": weave.repeat");
  }
  build_weave_maps(out, std::move(spec), fmt::format("{}: [weave]", toml_path));
}

}  // namespace

LoadedFabric load_fabric_description(const std::string& toml_path, const LoadOptions& options) {
  const std::string text = inputs::read_file_bytes(toml_path);
  const inputs::InputKind kind = fabric_input_kind(toml_path, text);
  if (kind == inputs::InputKind::Wif) {
    LoadedFabric out =
        fabric_from_wif(toml_path, options.resolution.value_or(kDefaultWeaveResolution));
    out.fabric.bake.radiance_dirs = 0;  // automatic, as for a [weave] without [bake]
    resolve_radiance_dirs(out.fabric);
    return out;
  }
  inputs::require_input_kind(kind, toml_path, inputs::InputKind::Fabric,
                             "this command needs a fabric (a .toml description, "
                             "docs/fabric-format.md, or a .wif draft); render, plan and report "
                             "error-time take scenes");
  LoadedFabric out;
  Fabric& f = out.fabric;
  f.inputs.push_back({"fabric", toml_path, inputs::xxh64_hex(text)});
  const toml::table root_table = inputs::parse_toml_text(text, toml_path);
  const TomlSection root(root_table, toml_path, "");
  root.check_keys({"name", "tile", "maps", "weave", "yarn", "sheen", "bake"});
  const std::string base_dir = std::filesystem::path(toml_path).parent_path().string();

  f.name = root.string("name").value_or(std::filesystem::path(toml_path).stem().string());
  auto maps = root.table("maps");
  auto weave_section = root.table("weave");
  auto tile = root.table("tile");
  if (maps && weave_section)
    throw_input_error(
        fmt::format("{}: [maps] and [weave] cannot both be given: a fabric's maps "
                    "come either from image files or from a weave",
                    root.where("weave")));
  if (!maps && !weave_section)
    throw_input_error(
        fmt::format("{}: no [maps] or [weave] section: say where the feature maps "
                    "come from (image files, or a weave name, matrix or WIF draft)",
                    toml_path));
  if (weave_section && tile)
    tile->fail("",
               "cannot be combined with [weave]: the tile is one repeat of the weave and its "
               "size follows from the yarn spacings ([weave.warp] spacing_mm, ...)");

  if (auto yarns = root.table_array("yarn")) {
    for (std::size_t i = 0; i < yarns->size(); ++i) {
      std::string default_name = weave_section ? (i == 0   ? "warp"
                                                  : i == 1 ? "weft"
                                                           : "")
                                               : std::string();
      if (default_name.empty()) default_name = fmt::format("yarn{}", i);
      f.yarns.push_back(parse_yarn((*yarns)[i], default_name));
      for (std::size_t j = 0; j < i; ++j)
        if (f.yarns[j].name == f.yarns[i].name)
          (*yarns)[i].fail("name", fmt::format("= \"{}\" is already the name of yarn[{}]; yarn "
                                               "names must be unique",
                                               f.yarns[i].name, j));
    }
  }
  if (auto sheen = root.table("sheen")) f.sheen = parse_sheen(*sheen);
  std::optional<int64_t> resolution;
  f.bake.radiance_dirs = 0;  // auto unless [bake] says otherwise
  if (auto bake = root.table("bake")) {
    f.bake = parse_bake(*bake);
    if (bake->has("resolution")) resolution = f.bake.resolution;
  }
  if (options.resolution) {
    if (*options.resolution < kMinResolution || *options.resolution > kMaxResolution)
      throw_input_error(fmt::format("resolution {} is out of range; valid range is [{}, {}]",
                                    *options.resolution, kMinResolution, kMaxResolution));
    resolution = *options.resolution;
    f.bake.resolution = *options.resolution;
  }

  if (maps) {
    out.source = FabricSource::Images;
    load_image_maps(out, *maps, tile, toml_path, base_dir, resolution);
  } else {
    if (f.yarns.empty()) f.yarns = default_weave_yarns();
    load_weave(out, *weave_section, base_dir, toml_path);
  }
  resolve_radiance_dirs(f);
  return out;
}

std::optional<FabricSettingsPeek> peek_fabric_settings(const std::string& toml_path,
                                                       const LoadOptions& options) {
  try {
    FabricSettingsPeek out;
    const std::string text = inputs::read_file_bytes(toml_path);
    if (fabric_input_kind(toml_path, text) == inputs::InputKind::Wif) {
      out.bake.resolution = options.resolution.value_or(kDefaultWeaveResolution);
      out.bake.radiance_dirs = 0;
      resolve_radiance_dirs(out.bake, {YarnMaterial{}.roughness});
      return out;
    }
    const toml::table root_table = inputs::parse_toml_text(text, toml_path);
    const TomlSection root(root_table, toml_path, "");
    out.bake.radiance_dirs = 0;
    if (auto bake = root.table("bake")) out.bake = parse_bake(*bake);
    if (options.resolution) out.bake.resolution = *options.resolution;
    std::vector<double> roughness;
    if (auto yarns = root.table_array("yarn"))
      for (std::size_t i = 0; i < yarns->size(); ++i)
        roughness.push_back((*yarns)[i].real("roughness", kRoughness).value_or(0.3));
    resolve_radiance_dirs(out.bake, roughness);
    if (auto maps = root.table("maps")) {
      out.image_maps = true;
      const auto file = maps->string("height");
      if (!file || file->empty()) return std::nullopt;
      const std::string base_dir = std::filesystem::path(toml_path).parent_path().string();
      const int side = inputs::map_image_side(inputs::resolve_relative(base_dir, *file));
      if (side < kMinResolution || side > kMaxResolution) return std::nullopt;
      out.bake.resolution = side;
    }
    return out;
  } catch (const Error&) {
    return std::nullopt;  // the full load reports it
  }
}

Fabric load_fabric(const std::string& toml_path) {
  return load_fabric_description(toml_path).fabric;
}

LoadedFabric fabric_from_named_weave(const std::string& weave_name, int resolution) {
  LoadedFabric out;
  out.source = FabricSource::NamedWeave;
  out.weave_label = weave_name;
  Fabric& f = out.fabric;
  f.name = weave_name;
  f.yarns = default_weave_yarns();
  f.bake.resolution = resolution;
  if (resolution < kMinResolution || resolution > kMaxResolution)
    throw_input_error(fmt::format("resolution {} is out of range; valid range is [{}, {}]",
                                  resolution, kMinResolution, kMaxResolution));
  weave::WeaveSpec spec;
  spec.matrix = weave::named_weave(weave_name);
  build_weave_maps(out, std::move(spec), fmt::format("weave \"{}\"", weave_name));
  return out;
}

LoadedFabric fabric_from_wif(const std::string& wif_path, int resolution) {
  LoadedFabric out;
  out.source = FabricSource::Wif;
  Fabric& f = out.fabric;
  f.yarns = default_weave_yarns();
  f.bake.resolution = resolution;
  if (resolution < kMinResolution || resolution > kMaxResolution)
    throw_input_error(fmt::format("resolution {} is out of range; valid range is [{}, {}]",
                                  resolution, kMinResolution, kMaxResolution));
  WifDraft draft = read_wif(wif_path);
  f.inputs.push_back({"wif", wif_path, inputs::hash_file(wif_path)});
  std::string stem = std::filesystem::path(wif_path).stem().string();
  f.name = draft.title.empty() ? stem : draft.title;
  out.weave_label =
      draft.title.empty() ? std::filesystem::path(wif_path).filename().string() : draft.title;
  build_weave_maps(out, std::move(draft.spec), wif_path);
  return out;
}

}  // namespace clothbake

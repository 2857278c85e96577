#include "bake/inputs/fabric_report.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "fabric/fabric_json.hpp"

namespace clothbake {
namespace {

using nlohmann::json;

json rgb(const Rgb& c) {
  return json::array({c[0], c[1], c[2]});
}

json stats(const inputs::ChannelStats& s) {
  return {{"min", s.min}, {"max", s.max}, {"mean", s.mean}, {"stddev", s.stddev}};
}

// Where a map came from: "file" (with its path), "weave", or how it was filled in.
std::pair<std::string, std::string> map_origin(const LoadedFabric& loaded,
                                               const std::string& role) {
  if (loaded.source != FabricSource::Images) return {"weave", ""};
  for (const auto& in : loaded.fabric.inputs)
    if (in.role == role) return {"file", in.path};
  if (role == "normal") return {"derived_from_height", ""};
  if (role == "albedo") return {"yarn_colors", ""};
  return {"default", ""};  // gap = 1 everywhere, yarn_id = 0 everywhere
}

json map_header(const LoadedFabric& loaded, const std::string& role) {
  auto [origin, file] = map_origin(loaded, role);
  return {{"origin", origin}, {"file", file.empty() ? json(nullptr) : json(file)}};
}

std::string describe_origin(const LoadedFabric& loaded, const std::string& role) {
  auto [origin, file] = map_origin(loaded, role);
  if (origin == "file") return file;
  if (origin == "weave") return "generated from the weave";
  if (origin == "derived_from_height") return "derived from the height map";
  if (origin == "yarn_colors") return "yarn colours";
  return role == "gap" ? "default: no gaps (I = 1)" : "default: yarn 0 everywhere";
}

std::string line_stats(const inputs::ChannelStats& s) {
  return fmt::format("min {:.6g}  max {:.6g}  mean {:.6g}  stddev {:.6g}", s.min, s.max, s.mean,
                     s.stddev);
}

std::string rgb_text(const Rgb& c) {
  return fmt::format("({:.4g}, {:.4g}, {:.4g})", c[0], c[1], c[2]);
}

}  // namespace

json fabric_parameters_json(const Fabric& f) {
  json yarns = json::array();
  for (std::size_t i = 0; i < f.yarns.size(); ++i) {
    const auto& y = f.yarns[i];
    yarns.push_back({{"id", i},
                     {"name", y.name},
                     {"roughness", y.roughness},
                     {"optical_thickness", y.optical_thickness},
                     {"specular_albedo", rgb(y.specular_albedo)},
                     {"diffuse_reflectance", rgb(y.diffuse_reflectance)},
                     {"diffuse_transmittance", rgb(y.diffuse_transmittance)},
                     {"color", rgb(y.color)}});
  }
  return {{"tile",
           {{"size_mm", f.tile_size_mm > 0 ? json(f.tile_size_mm) : json(nullptr)},
            {"height_unit", "tile side"}}},
          {"yarns", yarns},
          {"sheen", {{"color", rgb(f.sheen.color)}, {"roughness", f.sheen.roughness}}},
          {"bake", bake_settings_json(f.bake)}};
}

json weave_json(const LoadedFabric& loaded) {
  if (!loaded.weave) return nullptr;
  const weave::WeaveSpec& w = *loaded.weave;
  json end_colors = json::array(), pick_colors = json::array();
  for (const auto& c : w.end_colors)
    end_colors.push_back(rgb(c));
  for (const auto& c : w.pick_colors)
    pick_colors.push_back(rgb(c));
  auto geometry = [](const weave::YarnGeometry& g) {
    return json{{"spacing_mm", g.spacing_mm},
                {"width", g.width},
                {"height_mm", g.height_mm},
                {"twist_deg", g.twist_deg}};
  };
  weave::TileSize tile = weave::weave_tile_size(w);
  return {{"label", loaded.weave_label},
          {"picks", w.matrix.picks},
          {"ends", w.matrix.ends},
          {"matrix", w.matrix.to_rows()},
          {"matrix_convention", "rows = picks (weft), columns = ends (warp), 1 = warp on top"},
          {"end_colors", end_colors},
          {"pick_colors", pick_colors},
          {"warp", geometry(w.warp)},
          {"weft", geometry(w.weft)},
          {"per_thread_geometry", !w.end_geometry.empty() || !w.pick_geometry.empty()},
          {"tile_mm", {tile.width_mm, tile.height_mm}}};
}

json inspect_json(const LoadedFabric& loaded, const inputs::MapStats& s,
                  const std::vector<std::string>& warnings) {
  const Fabric& f = loaded.fabric;
  json maps;
  {
    json h = map_header(loaded, "height");
    h.update(stats(s.height));
    h["unit"] = "tile side";
    h["relief_mm"] =
        f.tile_size_mm > 0 ? json((s.height.max - s.height.min) * f.tile_size_mm) : json(nullptr);
    maps["height"] = h;
  }
  {
    json t = map_header(loaded, "tangent");
    t["x"] = stats(s.tangent[0]);
    t["y"] = stats(s.tangent[1]);
    t["z"] = stats(s.tangent[2]);
    const auto& d = s.tangent_directions;
    t["mean_abs_z"] = d.mean_abs_z;
    t["mean_elevation_deg"] = d.mean_elevation_deg;
    t["fraction_along_x"] = d.fraction_along_x;
    t["fraction_along_y"] = d.fraction_along_y;
    t["mean_axis_deg"] = d.mean_axis_deg;
    t["axial_concentration"] = d.axial_concentration;
    maps["tangent"] = t;
  }
  {
    json n = map_header(loaded, "normal");
    n["x"] = stats(s.normal[0]);
    n["y"] = stats(s.normal[1]);
    n["z"] = stats(s.normal[2]);
    n["mean_tilt_deg"] = s.mean_normal_tilt_deg;
    maps["normal"] = n;
  }
  {
    json g = map_header(loaded, "gap");
    g.update(stats(s.gap));
    g["gap_fraction"] = s.gap_fraction;
    maps["gap"] = g;
  }
  {
    json y = map_header(loaded, "yarn_id");
    json counts = json::array(), fractions = json::array();
    double texels = double(f.maps.texel_count());
    for (std::size_t i = 0; i < f.yarns.size(); ++i) {
      std::size_t c = i < s.yarn_texels.size() ? s.yarn_texels[i] : 0;
      counts.push_back(c);
      fractions.push_back(texels > 0 ? double(c) / texels : 0.0);
    }
    y["texels_per_yarn"] = counts;
    y["fraction_per_yarn"] = fractions;
    maps["yarn_id"] = y;
  }
  {
    json a = map_header(loaded, "albedo");
    a["r"] = stats(s.albedo[0]);
    a["g"] = stats(s.albedo[1]);
    a["b"] = stats(s.albedo[2]);
    maps["albedo"] = a;
  }
  json inputs = json::array();
  for (const auto& in : f.inputs)
    inputs.push_back({{"role", in.role}, {"path", in.path}, {"xxh64", in.xxh64}});
  json doc = {{"name", f.name},
              {"source", fabric_source_name(loaded.source)},
              {"resolution", f.maps.resolution},
              {"weave", weave_json(loaded)},
              {"maps", maps},
              {"inputs", inputs},
              {"warnings", warnings}};
  doc.update(fabric_parameters_json(f));
  return doc;
}

std::string inspect_text(const LoadedFabric& loaded, const inputs::MapStats& s,
                         const std::vector<std::string>& warnings) {
  const Fabric& f = loaded.fabric;
  std::string t;
  t += fmt::format("fabric      {}\n", f.name);
  t += fmt::format("source      {}{}\n", fabric_source_name(loaded.source),
                   loaded.weave_label.empty() ? "" : " (" + loaded.weave_label + ")");
  t += fmt::format("resolution  {} x {}\n", f.maps.resolution, f.maps.resolution);
  t += f.tile_size_mm > 0
           ? fmt::format("tile        {:.6g} mm wide; heights in tile-side units\n", f.tile_size_mm)
           : std::string("tile        no physical size; heights in tile-side units\n");
  if (loaded.weave) {
    const auto& m = loaded.weave->matrix;
    t += fmt::format("\nweave {} x {} (rows = picks, columns = ends, 1 = warp on top)\n", m.picks,
                     m.ends);
    auto rows = m.to_rows();
    std::size_t shown = std::min<std::size_t>(rows.size(), 32);
    for (std::size_t i = 0; i < shown; ++i)
      t += "  " + (rows[i].size() > 64 ? rows[i].substr(0, 64) + "..." : rows[i]) + "\n";
    if (shown < rows.size()) t += fmt::format("  ... {} more rows\n", rows.size() - shown);
  }
  t += "\nmaps\n";
  t += fmt::format("  height   [{}]\n           {} (tile-side units)",
                   describe_origin(loaded, "height"), line_stats(s.height));
  if (f.tile_size_mm > 0)
    t += fmt::format("\n           relief {:.4g} mm",
                     (s.height.max - s.height.min) * f.tile_size_mm);
  t += "\n";
  const char* axes[] = {"x", "y", "z"};
  t += fmt::format("  tangent  [{}]\n", describe_origin(loaded, "tangent"));
  for (int c = 0; c < 3; ++c)
    t += fmt::format("           {}: {}\n", axes[c], line_stats(s.tangent[c]));
  const auto& d = s.tangent_directions;
  t += fmt::format(
      "           along x (weft) {:.1f}%, along y (warp) {:.1f}%, mean |z| {:.3f}, "
      "mean elevation {:.1f} deg\n",
      100 * d.fraction_along_x, 100 * d.fraction_along_y, d.mean_abs_z, d.mean_elevation_deg);
  t += fmt::format("           axial mean direction {:.1f} deg from +x, concentration {:.3f}\n",
                   d.mean_axis_deg, d.axial_concentration);
  t += fmt::format("  normal   [{}]\n", describe_origin(loaded, "normal"));
  for (int c = 0; c < 3; ++c)
    t += fmt::format("           {}: {}\n", axes[c], line_stats(s.normal[c]));
  t += fmt::format("           mean tilt {:.2f} deg\n", s.mean_normal_tilt_deg);
  t += fmt::format("  gap      [{}]\n           {}\n           gap texels (I < 0.5): {:.2f}%\n",
                   describe_origin(loaded, "gap"), line_stats(s.gap), 100 * s.gap_fraction);
  t += fmt::format("  yarn_id  [{}]\n", describe_origin(loaded, "yarn_id"));
  double texels = double(f.maps.texel_count());
  for (std::size_t i = 0; i < f.yarns.size(); ++i) {
    std::size_t c = i < s.yarn_texels.size() ? s.yarn_texels[i] : 0;
    t += fmt::format("           {} '{}': {} texels ({:.1f}%)\n", i, f.yarns[i].name, c,
                     texels > 0 ? 100.0 * double(c) / texels : 0.0);
  }
  const char* rgb_axes[] = {"r", "g", "b"};
  t += fmt::format("  albedo   [{}]\n", describe_origin(loaded, "albedo"));
  for (int c = 0; c < 3; ++c)
    t += fmt::format("           {}: {}\n", rgb_axes[c], line_stats(s.albedo[c]));

  t += "\nyarns\n";
  for (std::size_t i = 0; i < f.yarns.size(); ++i) {
    const auto& y = f.yarns[i];
    t += fmt::format("  {} '{}': roughness {:.4g}, optical thickness {:.4g}, colour {}\n", i,
                     y.name, y.roughness, y.optical_thickness, rgb_text(y.color));
    t += fmt::format("      specular albedo {}, diffuse reflectance {}, diffuse transmittance {}\n",
                     rgb_text(y.specular_albedo), rgb_text(y.diffuse_reflectance),
                     rgb_text(y.diffuse_transmittance));
  }
  t += fmt::format("sheen       colour {}, roughness {:.4g}{}\n", rgb_text(f.sheen.color),
                   f.sheen.roughness,
                   f.sheen.color == Rgb{0, 0, 0} ? " (disabled: colour is zero)" : "");
  const BakeSettings& b = f.bake;
  t += fmt::format(
      "bake        resolution {}, parallax {}x{} dirs (cos > {:.3g}), visibility {}x{}, "
      "radiance {}x{} bins\n",
      b.resolution, b.parallax_dirs, b.parallax_dirs, b.parallax_min_cos, b.visibility_dirs,
      b.visibility_dirs, b.radiance_dirs, b.radiance_dirs);
  t += fmt::format(
      "            {} visibility clusters{}, visibility rank {}, compression {}, seed {}\n",
      b.clusters, b.clusters_by_yarn ? " (split by yarn)" : "", b.visibility_rank,
      !b.compress ? std::string("off")
      : b.compress_rank > 0
          ? fmt::format("C-PCA {} clusters x rank {}", std::max(b.compress_clusters, 1),
                        b.compress_rank)
          : fmt::format("C-PCA {} clusters, ranks chosen for the default target error",
                        std::max(b.compress_clusters, 1)),
      b.seed);
  t += "\ninputs\n";
  for (const auto& in : f.inputs)
    t += fmt::format("  {:<8} {}  {}\n", in.role, in.xxh64, in.path);
  if (!warnings.empty()) {
    t += "\nwarnings\n";
    for (const auto& w : warnings)
      t += "  " + w + "\n";
  }
  return t;
}

}  // namespace clothbake

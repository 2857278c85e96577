#include "bake/inputs/fabric_write.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "bake/inputs/map_image.hpp"
#include "common/error.hpp"
#include "common/temp_registry.hpp"
#include "common/version.hpp"

namespace clothbake {
namespace fs = std::filesystem;

namespace {

const char* const kMapRoles[] = {"height", "tangent", "normal", "gap", "yarn_id", "albedo"};

Image map_image(const FabricMaps& m, const std::string& role) {
  const int n = m.resolution;
  const std::size_t texels = m.texel_count();
  auto check = [&](std::size_t size) {
    if (size != texels)
      throw_internal_error(fmt::format("write_fabric_directory: {} map has {} texels, expected {}",
                                       role, size, texels));
  };
  if (role == "height" || role == "gap" || role == "yarn_id") {
    Image im(n, n, 1);
    if (role == "height") {
      check(m.height.size());
      std::copy(m.height.begin(), m.height.end(), im.pixels.begin());
    } else if (role == "gap") {
      check(m.gap.size());
      std::copy(m.gap.begin(), m.gap.end(), im.pixels.begin());
    } else {
      check(m.yarn_id.size());
      for (std::size_t i = 0; i < texels; ++i)
        im.pixels[i] = float(m.yarn_id[i]);
    }
    return im;
  }
  const std::vector<Vec3f>& v = role == "tangent"  ? m.tangent
                                : role == "normal" ? m.normal
                                                   : m.albedo;
  check(v.size());
  Image im(n, n, 3);
  for (std::size_t i = 0; i < texels; ++i)
    for (int c = 0; c < 3; ++c)
      im.pixels[i * 3 + c] = v[i][c];
  return im;
}

std::string number(double v) {
  return fmt::format("{}", v);
}

std::string rgb_text(const Rgb& c) {
  return fmt::format("[{}, {}, {}]", number(c[0]), number(c[1]), number(c[2]));
}

// Creates the missing ancestors of `dir` and returns them, outermost first.
std::vector<fs::path> create_parents(const fs::path& dir) {
  std::vector<fs::path> missing;
  for (fs::path p = dir.parent_path(); !p.empty() && !fs::exists(p); p = p.parent_path())
    missing.push_back(p);
  std::reverse(missing.begin(), missing.end());
  for (const auto& p : missing) {
    std::error_code ec;
    fs::create_directory(p, ec);
    if (ec)
      throw_input_error(fmt::format("{}: cannot create directory ({})", p.string(), ec.message()));
  }
  return missing;
}

}  // namespace

std::string toml_quote(const std::string& text) {
  std::string out = "\"";
  for (unsigned char ch : text) {
    if (ch == '"')
      out += "\\\"";
    else if (ch == '\\')
      out += "\\\\";
    else if (ch == '\n')
      out += "\\n";
    else if (ch == '\t')
      out += "\\t";
    else if (ch < 0x20 || ch == 0x7f)
      out += fmt::format("\\u{:04X}", unsigned(ch));
    else
      out += char(ch);
  }
  return out + "\"";
}

Rgb yarn_id_color(unsigned id) {
  // Hue steps of the golden ratio keep consecutive ids far apart on the colour wheel; full
  // saturation, value alternating so that ids 0..1 (warp/weft) read clearly on any screen.
  double hue = std::fmod(0.08 + id * 0.6180339887498949, 1.0) * 6.0;
  double value = id % 2 == 0 ? 0.95 : 0.75;
  double saturation = 0.85;
  int sector = int(hue);
  double f = hue - sector;
  double p = value * (1 - saturation), q = value * (1 - saturation * f),
         t = value * (1 - saturation * (1 - f));
  switch (sector % 6) {
    case 0:
      return {value, t, p};
    case 1:
      return {q, value, p};
    case 2:
      return {p, value, t};
    case 3:
      return {p, q, value};
    case 4:
      return {t, p, value};
    default:
      return {value, p, q};
  }
}

Image preview_image(const FabricMaps& m, const std::string& role) {
  Image data = map_image(m, role);
  const std::size_t texels = m.texel_count();
  Image out(m.resolution, m.resolution, role == "height" || role == "gap" ? 1 : 3);
  if (role == "height") {
    auto [lo, hi] = std::minmax_element(m.height.begin(), m.height.end());
    double range = double(*hi) - double(*lo);
    for (std::size_t i = 0; i < texels; ++i)
      out.pixels[i] = range > 0 ? float((double(m.height[i]) - *lo) / range) : 0.5f;
  } else if (role == "gap") {
    out.pixels = data.pixels;
  } else if (role == "tangent" || role == "normal") {
    for (std::size_t i = 0; i < data.pixels.size(); ++i)
      out.pixels[i] = 0.5f * data.pixels[i] + 0.5f;
  } else if (role == "yarn_id") {
    for (std::size_t i = 0; i < texels; ++i) {
      Rgb c = yarn_id_color(m.yarn_id[i]);
      for (int ch = 0; ch < 3; ++ch)
        out.pixels[i * 3 + ch] = float(c[ch]);
    }
  } else {
    for (std::size_t i = 0; i < data.pixels.size(); ++i)
      out.pixels[i] = float(inputs::linear_to_srgb(data.pixels[i]));
  }
  return out;
}

std::string fabric_toml_text(const Fabric& f, const std::string& comment) {
  std::string t;
  t +=
      fmt::format("# Written by clothbake {} (docs/fabric-format.md).\n", CLOTHBAKE_VERSION_STRING);
  if (!comment.empty()) t += "# " + comment + "\n";
  t +=
      "# The maps below are float EXR files beside this file; edit the parameters or the maps and\n"
      "# bake this file. The *.preview.png images are for viewing only.\n\n";
  t += fmt::format("name = {}\n\n", toml_quote(f.name));
  if (f.tile_size_mm > 0) {
    t += "[tile]\n";
    t += fmt::format("size = {}  # physical width of the tile (one repeat)\n",
                     number(f.tile_size_mm));
    t += "units = \"mm\"\n\n";
  }
  t += "[maps]\n";
  t += "height = \"height.exr\"\n";
  t += f.tile_size_mm > 0
           ? fmt::format("height_units = \"tile\"  # stored in tile-side units: 1.0 = {} mm\n",
                         number(f.tile_size_mm))
           : std::string("height_units = \"tile\"  # stored in tile-side units\n");
  t += "tangent = \"tangent.exr\"\n";
  t += "normal = \"normal.exr\"\n";
  t += "gap = \"gap.exr\"\n";
  t += "yarn_id = \"yarn_id.exr\"\n";
  t += "albedo = \"albedo.exr\"  # linear RGB; replaces the yarn colours below\n\n";
  for (const auto& y : f.yarns) {
    t += "[[yarn]]\n";
    t += fmt::format("name = {}\n", toml_quote(y.name));
    t += fmt::format("roughness = {}\n", number(y.roughness));
    t += fmt::format("optical_thickness = {}\n", number(y.optical_thickness));
    t += fmt::format("specular_albedo = {}\n", rgb_text(y.specular_albedo));
    t += fmt::format("diffuse_reflectance = {}\n", rgb_text(y.diffuse_reflectance));
    t += fmt::format("diffuse_transmittance = {}\n", rgb_text(y.diffuse_transmittance));
    t += fmt::format("color = {}\n\n", rgb_text(y.color));
  }
  t += "[sheen]\n";
  t += fmt::format("color = {}\n", rgb_text(f.sheen.color));
  t += fmt::format("roughness = {}\n\n", number(f.sheen.roughness));
  const BakeSettings& b = f.bake;
  t += "[bake]\n";
  t += fmt::format("resolution = {}\n", b.resolution);
  t += fmt::format("parallax_dirs = {}\n", b.parallax_dirs);
  t += fmt::format("parallax_min_cos = {}\n", number(b.parallax_min_cos));
  t += fmt::format("parallax_max_error = {}\n", number(b.parallax_max_error));
  t += fmt::format("visibility_dirs = {}\n", b.visibility_dirs);
  t += fmt::format("radiance_dirs = {}\n", b.radiance_dirs);
  t += fmt::format("clusters = {}\n", b.clusters);
  t += fmt::format("clusters_by_yarn = {}\n", b.clusters_by_yarn ? "true" : "false");
  t += fmt::format("visibility_rank = {}\n", b.visibility_rank);
  t += fmt::format("compress = {}\n", b.compress ? "true" : "false");
  t += fmt::format("compress_clusters = {}\n", b.compress_clusters);
  t += fmt::format("compress_rank = {}\n", b.compress_rank);
  t += fmt::format("seed = {}\n", b.seed);
  return t;
}

std::vector<WrittenFile> write_fabric_directory(const Fabric& fabric, const std::string& dir,
                                                const std::string& comment) {
  fs::path target = fs::path(dir).lexically_normal();
  if (!target.empty() && target.filename().empty()) target = target.parent_path();  // "out/"
  if (target.empty() || target.filename().empty() || target.filename() == "." ||
      target.filename() == "..")
    throw_input_error(fmt::format("{}: not a valid output directory name", dir));
  std::error_code ec;
  bool target_exists = fs::exists(target, ec);
  if (target_exists && !fs::is_directory(target, ec))
    throw_input_error(fmt::format("{}: exists and is not a directory", dir));

  // Build everything in memory first: a bad map fails before anything touches the disk.
  std::vector<std::pair<std::string, Image>> images;
  for (const char* role : kMapRoles)
    images.emplace_back(role, map_image(fabric.maps, role));
  const std::string toml = fabric_toml_text(fabric, comment);

  std::vector<fs::path> created_parents = create_parents(target);
  static std::atomic<unsigned> counter{0};
  const fs::path temp =
      target.parent_path() /
      fmt::format(".{}.tmp-{}-{}", target.filename().string(), ::getpid(), counter.fetch_add(1));
  std::vector<WrittenFile> written;
  // The temporary directory and each file in it are registered for the signal handlers
  // (common/temp_registry.hpp): SIGINT/SIGTERM/SIGHUP remove the files, then the directory.
  std::vector<int> slots;
  auto track = [&](const fs::path& path, bool directory) {
    slots.push_back(register_temp_path(fs::absolute(path, ec).c_str(), directory));
  };
  auto untrack = [&] {
    for (const int slot : slots)
      unregister_temp_path(slot);
    slots.clear();
  };
  auto cleanup = [&] {
    std::error_code ignored;
    fs::remove_all(temp, ignored);
    untrack();
    for (auto it = created_parents.rbegin(); it != created_parents.rend(); ++it)
      fs::remove(*it, ignored);  // only removes directories that are still empty
  };
  try {
    track(temp, true);
    if (!fs::create_directory(temp, ec) || ec)
      throw_input_error(fmt::format("{}: cannot create temporary directory ({})", temp.string(),
                                    ec ? ec.message() : "already exists"));
    std::vector<std::string> names;
    for (const auto& [role, image] : images) {
      track(temp / (role + ".exr"), false);
      write_image((temp / (role + ".exr")).string(), image, PixelType::Float32);
      names.push_back(role + ".exr");
      written.push_back({role, (target / (role + ".exr")).string()});
    }
    for (const auto& [role, image] : images) {
      std::string name = role + ".preview.png";
      track(temp / name, false);
      write_image((temp / name).string(), preview_image(fabric.maps, role), PixelType::UInt8);
      names.push_back(name);
      written.push_back({role + "_preview", (target / name).string()});
    }
    {
      track(temp / "fabric.toml", false);
      std::ofstream out(temp / "fabric.toml", std::ios::binary);
      out << toml;
      out.close();
      if (!out) throw_input_error(fmt::format("{}: cannot write", (temp / "fabric.toml").string()));
      names.push_back("fabric.toml");
      written.push_back({"fabric", (target / "fabric.toml").string()});
    }
    // Move into place: a fresh directory in one rename; into an existing one file by file, so that
    // its other files stay.
    if (!fs::exists(target, ec)) {
      fs::rename(temp, target, ec);
      if (ec)
        throw_input_error(fmt::format("{}: cannot move output into place ({})", dir, ec.message()));
    } else {
      for (const auto& name : names) {
        fs::rename(temp / name, target / name, ec);
        if (ec)
          throw_input_error(
              fmt::format("{}: cannot move {} into place ({})", dir, name, ec.message()));
      }
      fs::remove(temp, ec);
    }
  } catch (...) {
    cleanup();
    throw;
  }
  untrack();
  return written;
}

}  // namespace clothbake

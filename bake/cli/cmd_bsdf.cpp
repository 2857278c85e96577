// clothbake bsdf: evaluate the cloth BSDF of one texel (paper Eq. 3-4, model/cloth_bsdf.hpp) for a
// pair of directions, or write a slice of one lobe over a hemisphere as an image (docs/model.md).
//
//   clothbake bsdf --tangent x,y,z --roughness S --thickness T --albedo A
//                  [--diffuse-reflectance R] [--diffuse-transmittance R]
//                  [--sheen-color C --sheen-roughness R [--sheen-convention published|converged]]
//                  [--gap I] [--visibility V]
//                  --wi x,y,z (--wo x,y,z | --slice LOBE -o FILE [--resolution N]
//                  [--hemisphere upper|lower]) [--json]
//
// Colours (A, R, C) are one number or r,g,b. Bad arguments exit with code 1 and a message naming
// the option; an unwritable output exits with 2 and leaves nothing at the output path.
#include <fmt/format.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <system_error>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "model/cloth_bsdf.hpp"
#include "model/directions.hpp"
#include "model/lobe_integral.hpp"
#include "model/parameter_text.hpp"
#include "render/image_output.hpp"

namespace clothbake::cli {
namespace {

using model::Rgb;
using model::Vec3d;

struct BsdfOptions {
  std::string tangent, roughness, thickness, albedo;
  std::string diffuse_reflectance = "0", diffuse_transmittance = "0";
  std::string sheen_color = "0", sheen_roughness = "0.5", gap = "1", visibility = "1";
  std::string sheen_convention = "published";
  std::string wi, wo;
  std::string slice, output, hemisphere = "auto";
  int resolution = 256;
  bool json = false;
};

// A finite number, the whole string; throws CLI::ValidationError naming the option. "inf" is
// accepted only where allow_inf says so.
double parse_number(const std::string& text, const std::string& option, bool allow_inf = false) {
  std::string s = text;
  while (!s.empty() && std::isspace((unsigned char)s.back()))
    s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && std::isspace((unsigned char)s[start]))
    ++start;
  s = s.substr(start);
  if (allow_inf && (s == "inf" || s == "+inf" || s == "infinity"))
    return std::numeric_limits<double>::infinity();
  double value = 0;
  std::size_t used = 0;
  try {
    value = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != s.size() || !std::isfinite(value))
    throw CLI::ValidationError(option, fmt::format("expected a finite number{}, got '{}'",
                                                   allow_inf ? " or inf" : "", text));
  return value;
}

// "v" or "r,g,b".
Rgb<double> parse_color(const std::string& text, const std::string& option) {
  if (text.find(',') == std::string::npos) return Rgb<double>(parse_number(text, option));
  const auto v = parse_vec3(text, option);
  for (double c : v)
    if (!std::isfinite(c))
      throw CLI::ValidationError(option, fmt::format("expected finite numbers, got '{}'", text));
  return {v[0], v[1], v[2]};
}

// A direction option, normalised (the BSDF takes unit vectors).
Vec3d unit_direction(const std::string& text, const std::string& option) {
  const auto v = parse_direction(text, option);
  const Vec3d d{v[0], v[1], v[2]};
  return d / model::length(d);
}

const char* option_of_field(const std::string& field) {
  if (field == "tangent") return "--tangent";
  if (field == "roughness") return "--roughness";
  if (field == "optical_thickness") return "--thickness";
  if (field == "specular_albedo") return "--albedo";
  if (field == "diffuse_reflectance") return "--diffuse-reflectance";
  if (field == "diffuse_transmittance") return "--diffuse-transmittance";
  if (field == "gap") return "--gap";
  if (field == "sheen_color") return "--sheen-color";
  if (field == "sheen_roughness") return "--sheen-roughness";
  return "bsdf";
}

nlohmann::json rgb_json(const Rgb<double>& c) {
  return nlohmann::json::array({c.r, c.g, c.b});
}
nlohmann::json vec_json(const Vec3d& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

bool is_transmission_lobe(const std::string& name) {
  return name == "specular_transmission" || name == "diffuse_transmission";
}

Rgb<double> slice_value(const model::LobeValues<double>& f, const std::string& lobe) {
  if (lobe == "total") return f.total;
  model::Lobe l = model::Lobe::SpecularReflection;
  if (!model::parse_lobe(lobe, l)) return {};
  return f[l];
}

struct SliceResult {
  Rgb<double> max_value;
  Rgb<double> pixel_sum;  // sum over the pixels of f |cos theta_o| dw: the image's integral
  model::LobeIntegral
      integral;        // importance-sampled integral of f |cos theta_o| over the hemisphere
  double scale = 1.0;  // pixel = value * scale (1 for EXR)
  bool upper = true;
};

// Samples of the slice's integral_cos estimate: a standard error of ~0.2 % of a typical lobe's
// albedo, in ~0.2 s.
constexpr uint64_t kIntegralSamples = uint64_t(1) << 18;

// Writes the slice image to a temporary file beside `path` and renames it into place.
SliceResult write_slice(const model::ClothBsdf<double>& bsdf, const Vec3d& wi, double visibility,
                        const BsdfOptions& o) {
  SliceResult result;
  if (o.hemisphere == "upper")
    result.upper = true;
  else if (o.hemisphere == "lower")
    result.upper = false;
  else  // auto: where the lobe lives for this wi
    result.upper = (wi.z >= 0) != is_transmission_lobe(o.slice);
  const int n = o.resolution;
  model::DirectionGrid<double> grid{n, 0.0};
  Image image(n, n, 3);
  const double pixel_solid_angle = grid.bin_solid_angle();
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      // Image right = local +x, image up = local +y: row 0 is the top (v = 1).
      Vec3d wo = grid.direction((x + 0.5) / n, 1.0 - (y + 0.5) / n);
      if (!result.upper) wo.z = -wo.z;
      const Rgb<double> v = slice_value(bsdf.eval(wi, wo, visibility), o.slice);
      for (int c = 0; c < 3; ++c)
        image.at(x, y, c) = float(v[c]);
      result.max_value = {std::max(result.max_value.r, v.r), std::max(result.max_value.g, v.g),
                          std::max(result.max_value.b, v.b)};
      result.pixel_sum += v * (std::abs(wo.z) * pixel_solid_angle);
    }
  // The pixel sum misses lobes narrower than a pixel (roughness <= 1e-3); the reported integral
  // follows the BSDF's sampler instead (model/lobe_integral.hpp).
  result.integral = model::lobe_integral_cos(
      bsdf, wi, visibility,
      [&](const model::LobeValues<double>& f) { return slice_value(f, o.slice); }, result.upper,
      kIntegralSamples, /*seed=*/1);
  const std::filesystem::path path(o.output);
  std::string ext = path.extension().string();
  for (char& ch : ext)
    ch = char(std::tolower((unsigned char)ch));
  PixelType type = PixelType::Float32;
  if (ext == ".png") type = PixelType::UInt8;
  if (ext == ".tif" || ext == ".tiff") type = PixelType::UInt16;
  if (type != PixelType::Float32) {
    // Integer formats clamp to [0, 1]: normalise by the largest value (reported as "scale").
    const double peak = result.max_value.max_component();
    result.scale = peak > 0 ? 1.0 / peak : 1.0;
    for (float& p : image.pixels)
      p = float(p * result.scale);
  }
  render::write_image_atomically(path, image, type);
  return result;
}

Action setup_bsdf(CLI::App& app) {
  auto o = std::make_shared<BsdfOptions>();
  app.add_option("--tangent", o->tangent, "fibre tangent x,y,z in the local frame (z = normal)")
      ->required();
  app.add_option("--roughness", o->roughness, "SGGX fibre roughness sigma in [1e-4, 1]")
      ->required();
  app.add_option("--thickness", o->thickness, "SpongeCake optical thickness T >= 0 (or inf)")
      ->required();
  app.add_option("--albedo", o->albedo, "specular albedo alpha: v or r,g,b in [0, 1]")->required();
  app.add_option("--diffuse-reflectance", o->diffuse_reflectance,
                 "diffuse reflectance R_d: v or r,g,b (default 0)");
  app.add_option("--diffuse-transmittance", o->diffuse_transmittance,
                 "diffuse transmittance T_d: v or r,g,b (default 0)");
  app.add_option("--sheen-color", o->sheen_color, "sheen colour: v or r,g,b (default 0: no sheen)");
  app.add_option("--sheen-roughness", o->sheen_roughness,
                 "sheen roughness in [1e-4, 1] (default 0.5)");
  app.add_option("--sheen-convention", o->sheen_convention,
                 "sheen table: published (Zeltner et al.'s, as Cycles ships it; default) or "
                 "converged (docs/sheen.md)")
      ->check(CLI::IsMember({"published", "converged"}));
  app.add_option("--gap", o->gap, "yarn indicator I in [0, 1]: 1 yarn, 0 gap (default 1)");
  app.add_option("--visibility", o->visibility, "visibility V(x', wi) in [0, 1] (default 1)");
  app.add_option("--wi", o->wi, "direction towards the light x,y,z (normalised)")->required();
  app.add_option("--wo", o->wo, "direction towards the viewer x,y,z (normalised)");
  app.add_option("--slice", o->slice,
                 "write LOBE (a lobe name or 'total') over a hemisphere of wo for the given wi");
  app.add_option("-o,--output", o->output, "slice image (.exr float; .png/.tif scaled by 1/max)");
  app.add_option("--resolution", o->resolution, "slice image side in pixels (default 256)")
      ->check(CLI::Range(8, 4096));
  app.add_option("--hemisphere", o->hemisphere,
                 "slice hemisphere: upper, lower or auto (the side where the lobe lives)")
      ->check(CLI::IsMember({"upper", "lower", "auto"}));
  add_json_flag(app, o->json, "print the values as JSON on stdout");
  return [o] {
    model::TexelParams<double> p;
    {
      const auto t = parse_vec3(o->tangent, "--tangent");
      p.tangent = {t[0], t[1], t[2]};
    }
    p.roughness = parse_number(o->roughness, "--roughness");
    p.optical_thickness = parse_number(o->thickness, "--thickness", true);
    p.specular_albedo = parse_color(o->albedo, "--albedo");
    p.diffuse_reflectance = parse_color(o->diffuse_reflectance, "--diffuse-reflectance");
    p.diffuse_transmittance = parse_color(o->diffuse_transmittance, "--diffuse-transmittance");
    p.sheen_color = parse_color(o->sheen_color, "--sheen-color");
    p.sheen_roughness = parse_number(o->sheen_roughness, "--sheen-roughness");
    model::parse_sheen_convention(o->sheen_convention, p.sheen_convention);  // checked above
    p.gap = parse_number(o->gap, "--gap");
    const double visibility = parse_number(o->visibility, "--visibility");
    if (!(visibility >= 0 && visibility <= 1))
      throw CLI::ValidationError("--visibility", "must be in [0, 1]");
    const model::ParamsProblem problem = model::validate_texel_params(p);
    if (!problem.ok()) throw CLI::ValidationError(option_of_field(problem.field), problem.message);
    const Vec3d wi = unit_direction(o->wi, "--wi");
    std::optional<Vec3d> wo;
    if (!o->wo.empty()) wo = unit_direction(o->wo, "--wo");
    const bool slicing = !o->slice.empty();
    if (slicing) {
      model::Lobe lobe = model::Lobe::SpecularReflection;
      if (o->slice == "delta_transmission")
        throw CLI::ValidationError(
            "--slice", "delta_transmission is a Dirac delta along -wi: it has no slice");
      if (o->slice != "total" && !model::parse_lobe(o->slice, lobe))
        throw CLI::ValidationError(
            "--slice", fmt::format("unknown lobe '{}' (specular_reflection, specular_transmission, "
                                   "diffuse_reflection, diffuse_transmission, sheen, total)",
                                   o->slice));
      if (o->output.empty()) throw CLI::ValidationError("-o", "--slice needs -o FILE");
      std::string ext = std::filesystem::path(o->output).extension().string();
      for (char& ch : ext)
        ch = char(std::tolower((unsigned char)ch));
      if (ext != ".exr" && ext != ".png" && ext != ".tif" && ext != ".tiff")
        throw CLI::ValidationError("-o", fmt::format("'{}': the extension must be .exr, .png, "
                                                     ".tif or .tiff",
                                                     o->output));
    } else {
      if (!wo) throw CLI::ValidationError("--wo", "--wo is required unless --slice is given");
      if (!o->output.empty()) throw CLI::ValidationError("-o", "-o is only used with --slice");
    }
    take_warnings();
    if (model::energy_excess(p) > 1e-12)
      warn(
          fmt::format("albedo + diffuse reflectance + diffuse transmittance exceeds 1 by {:.3g} "
                      "in some channel: the BSDF may not conserve energy",
                      model::energy_excess(p)));

    const model::ClothBsdf<double> bsdf(p);
    nlohmann::json out = {{"wi", vec_json(wi)}, {"visibility", visibility}};
    std::ostringstream text;
    if (wo) {
      const auto f = bsdf.eval(wi, *wo, visibility);
      const auto pa = bsdf.technique_probabilities(*wo);
      nlohmann::json lobes = nlohmann::json::object();
      for (int l = 0; l < model::kLobeCount; ++l)
        lobes[model::lobe_name(model::Lobe(l))] = rgb_json(f[model::Lobe(l)]);
      nlohmann::json probabilities = nlohmann::json::object();
      for (int t = 0; t < model::kTechniqueCount; ++t)
        probabilities[model::technique_name(model::Technique(t))] = pa.p[t];
      out["wo"] = vec_json(*wo);
      out["lobes"] = lobes;
      out["total"] = rgb_json(f.total);
      out["pdf"] = bsdf.pdf(wi, *wo);
      out["technique_probabilities"] = probabilities;
      out["units"] = {{"lobes",
                       "1/sr, no cosine factor; delta_transmission is the weight W of "
                       "W delta(wi + wo) / |wi.z| and is not part of total"},
                      {"pdf", "1/sr, density of wi from sampling given wo, continuous techniques"}};
      text << fmt::format("wi = ({:.6g}, {:.6g}, {:.6g})  wo = ({:.6g}, {:.6g}, {:.6g})  V = {}\n",
                          wi.x, wi.y, wi.z, wo->x, wo->y, wo->z, visibility);
      for (int l = 0; l < model::kLobeCount; ++l) {
        const auto v = f[model::Lobe(l)];
        text << fmt::format("{:<22} {:.9g} {:.9g} {:.9g}{}\n", model::lobe_name(model::Lobe(l)),
                            v.r, v.g, v.b,
                            model::Lobe(l) == model::Lobe::DeltaTransmission
                                ? "  (weight of delta(wi + wo), not in total)"
                                : "");
      }
      text << fmt::format("{:<22} {:.9g} {:.9g} {:.9g}\n", "total", f.total.r, f.total.g,
                          f.total.b);
      text << fmt::format("{:<22} {:.9g}\n", "pdf", bsdf.pdf(wi, *wo));
    }
    if (slicing) {
      const SliceResult s = write_slice(bsdf, wi, visibility, *o);
      out["slice"] = {{"lobe", o->slice},
                      {"output", o->output},
                      {"resolution", o->resolution},
                      {"hemisphere", s.upper ? "upper" : "lower"},
                      {"projection",
                       "equal-area concentric square-to-hemisphere map (model/directions.hpp); "
                       "image right = +x, up = +y"},
                      {"pixel", "f(wi, wo) in 1/sr, times scale"},
                      {"scale", s.scale},
                      {"max", rgb_json(s.max_value)},
                      {"integral_cos", rgb_json(s.integral.mean)},
                      {"integral_cos_standard_error", rgb_json(s.integral.standard_error)},
                      {"integral_cos_samples", s.integral.samples},
                      {"integral_cos_pixel_sum", rgb_json(s.pixel_sum)}};
      text << fmt::format("wrote {} ({} over the {} hemisphere, {}x{}, scale {:.6g})\n", o->output,
                          o->slice, s.upper ? "upper" : "lower", o->resolution, o->resolution,
                          s.scale);
    }
    out["warnings"] = take_warnings();
    if (o->json)
      print_json(out);
    else {
      std::cout << text.str();
      std::cout.flush();
    }
    return 0;
  };
}

const bool bsdf_registered = register_command(
    {"bsdf", "Evaluate the cloth BSDF (Eq. 3-4) of one texel, or write a lobe slice image",
     setup_bsdf});

}  // namespace
}  // namespace clothbake::cli

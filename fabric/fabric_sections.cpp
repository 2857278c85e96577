#include "fabric/fabric_sections.hpp"

#include <cmath>
#include <cstring>

#include "common/error.hpp"
#include "fabric/fabric_json.hpp"
#include "formats/reader/map_encoding.hpp"
#include "formats/writer/half_float.hpp"
#include "formats/writer/map_encoding.hpp"

namespace clothbake {
namespace {

using formats::make_array_section;
using formats::make_record_section;
using formats::Section;
using reader::FabricInfoRecord;
using reader::SectionType;
using reader::YarnMaterialRecord;

void copy_rgb(double out[3], const Rgb& in) {
  for (int c = 0; c < 3; ++c)
    out[c] = in[c];
}

// Cuts `name` to at most max_bytes without splitting a UTF-8 sequence.
std::string cut_utf8(const std::string& name, std::size_t max_bytes) {
  if (name.size() <= max_bytes) return name;
  std::size_t cut = max_bytes;
  while (cut > 0 && (static_cast<unsigned char>(name[cut]) & 0xc0) == 0x80)
    --cut;
  return name.substr(0, cut);
}

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");

void check_texels(SectionType type, std::size_t have, std::size_t texels, uint32_t n) {
  if (have != texels)
    throw_input_error(std::string("feature map '") + reader::section_type_name(type) + "' has " +
                      std::to_string(have) + " texels, expected " + std::to_string(texels) + " (" +
                      std::to_string(n) + " x " + std::to_string(n) + ")");
}

// yarn_id, the one map stored as a plain typed array.
Section yarn_id_map(const std::vector<uint16_t>& values, std::size_t texels, uint32_t n) {
  check_texels(SectionType::YarnIdMap, values.size(), texels, n);
  return make_array_section<uint16_t>(SectionType::YarnIdMap, 0, values, {n, n});
}

// Refuses NaN/Inf before the 16-bit codes would hide them: names the map, the element and the
// texel.
void check_finite_map(SectionType type, const float* values, std::size_t count, uint32_t channels,
                      uint32_t n) {
  for (std::size_t i = 0; i < count; ++i)
    if (!std::isfinite(values[i])) {
      // make_array_section's wording: element index and [y, x(, channel)].
      const std::size_t t = i / channels;
      throw_input_error(std::string("refusing to write a non-finite value: ") +
                        reader::section_type_name(type) + " element " + std::to_string(i) + " [" +
                        std::to_string(t / n) + ", " + std::to_string(t % n) +
                        (channels > 1 ? ", " + std::to_string(i % channels) : "") + "] is " +
                        (std::isnan(values[i]) ? "NaN" : "Inf"));
    }
}

Section packed_height(const std::vector<float>& height, std::size_t texels, uint32_t n) {
  check_texels(SectionType::HeightMap, height.size(), texels, n);
  check_finite_map(SectionType::HeightMap, height.data(), height.size(), 1, n);
  std::vector<reader::Half> codes(height.size());
  for (std::size_t t = 0; t < height.size(); ++t) {
    if (!(std::fabs(height[t]) <= 65504.0f))
      throw_input_error("height map texel x=" + std::to_string(t % n) +
                        ", y=" + std::to_string(t / n) + " is " + std::to_string(height[t]) +
                        " tile sides, beyond the f16 range of the stored map (|h| <= 65504)");
    codes[t] = formats::float_to_half(height[t]);
  }
  return make_array_section<reader::Half>(SectionType::HeightMap, 0, codes, {n, n});
}

Section packed_unit_vectors(SectionType type, const std::vector<Vec3f>& values, std::size_t texels,
                            uint32_t n) {
  check_texels(type, values.size(), texels, n);
  check_finite_map(type, values.empty() ? nullptr : values.front().data(), values.size() * 3, 3, n);
  std::vector<int16_t> codes(values.size() * 2);
  for (std::size_t t = 0; t < values.size(); ++t)
    formats::unit_to_octahedral(values[t].data(), codes.data() + 2 * t);
  return make_array_section<int16_t>(type, 0, codes, {n, n, 2});
}

Section packed_unorm(SectionType type, const float* values, std::size_t count, uint32_t channels,
                     std::size_t texels, uint32_t n) {
  check_texels(type, count / channels, texels, n);
  check_finite_map(type, values, count, channels, n);
  std::vector<uint16_t> codes(count);
  for (std::size_t i = 0; i < count; ++i)
    codes[i] = formats::float_to_unorm16(values[i]);
  std::vector<uint32_t> dims = {n, n};
  if (channels > 1) dims.push_back(channels);
  return make_array_section<uint16_t>(type, 0, codes, dims);
}

}  // namespace

std::vector<Section> fabric_record_sections(const Fabric& fabric) {
  if (fabric.yarns.size() > 65536)
    throw_input_error("fabric '" + fabric.name + "' has " + std::to_string(fabric.yarns.size()) +
                      " yarn materials; at most 65536 are supported (yarn ids are 16-bit)");
  FabricInfoRecord info;
  std::memset(&info, 0, sizeof info);
  info.resolution = uint32_t(std::max(fabric.maps.resolution, 0));
  info.yarn_count = uint32_t(fabric.yarns.size());
  copy_rgb(info.sheen_color, fabric.sheen.color);
  info.sheen_roughness = fabric.sheen.roughness;
  info.tile_size_mm = fabric.tile_size_mm;

  std::vector<YarnMaterialRecord> yarns(fabric.yarns.size());
  for (std::size_t i = 0; i < fabric.yarns.size(); ++i) {
    const YarnMaterial& in = fabric.yarns[i];
    YarnMaterialRecord& out = yarns[i];
    std::memset(&out, 0, sizeof out);
    const std::string name = cut_utf8(in.name, reader::kYarnNameBytes - 1);
    std::memcpy(out.name, name.data(), name.size());
    out.roughness = in.roughness;
    out.optical_thickness = in.optical_thickness;
    copy_rgb(out.specular_albedo, in.specular_albedo);
    copy_rgb(out.diffuse_reflectance, in.diffuse_reflectance);
    copy_rgb(out.diffuse_transmittance, in.diffuse_transmittance);
    copy_rgb(out.color, in.color);
  }
  // Records hold doubles: check them here, as the u8 payload hides them from the NaN check.
  auto check = [&](double v, const std::string& what) {
    if (!std::isfinite(v))
      throw_input_error("refusing to write a non-finite value: " + what + " is " +
                        (std::isnan(v) ? "NaN" : "Inf"));
  };
  for (int c = 0; c < 3; ++c)
    check(info.sheen_color[c], "fabric_info sheen_color[" + std::to_string(c) + "]");
  check(info.sheen_roughness, "fabric_info sheen_roughness");
  check(info.tile_size_mm, "fabric_info tile_size_mm");
  for (std::size_t i = 0; i < yarns.size(); ++i) {
    const std::string at =
        "yarn_materials element " + std::to_string(i) + " ('" + fabric.yarns[i].name + "') ";
    const auto& y = yarns[i];
    check(y.roughness, at + "roughness");
    check(y.optical_thickness, at + "optical_thickness");
    for (int c = 0; c < 3; ++c) {
      check(y.specular_albedo[c], at + "specular_albedo");
      check(y.diffuse_reflectance[c], at + "diffuse_reflectance");
      check(y.diffuse_transmittance[c], at + "diffuse_transmittance");
      check(y.color[c], at + "color");
    }
  }
  std::vector<Section> sections;
  sections.push_back(
      make_record_section<FabricInfoRecord>(SectionType::FabricInfo, 0, std::span(&info, 1)));
  sections.push_back(make_record_section<YarnMaterialRecord>(SectionType::YarnMaterials, 0, yarns));
  return sections;
}

std::vector<Section> feature_map_codes(const FabricMaps& maps) {
  if (maps.resolution <= 0)
    throw_input_error("feature maps have resolution " + std::to_string(maps.resolution) +
                      "; expected a positive N");
  const uint32_t n = uint32_t(maps.resolution);
  const std::size_t texels = maps.texel_count();
  std::vector<Section> sections;
  sections.push_back(packed_height(maps.height, texels, n));
  sections.push_back(packed_unit_vectors(SectionType::TangentMap, maps.tangent, texels, n));
  sections.push_back(packed_unit_vectors(SectionType::NormalMap, maps.normal, texels, n));
  sections.push_back(
      packed_unorm(SectionType::GapMap, maps.gap.data(), maps.gap.size(), 1, texels, n));
  sections.push_back(yarn_id_map(maps.yarn_id, texels, n));
  sections.push_back(packed_unorm(SectionType::AlbedoMap,
                                  maps.albedo.empty() ? nullptr : maps.albedo.front().data(),
                                  maps.albedo.size() * 3, 3, texels, n));
  return sections;
}

nlohmann::json fabric_metadata(const Fabric& fabric) {
  nlohmann::json j;
  j["name"] = fabric.name;
  j["resolution"] = fabric.maps.resolution;
  j["tile_size_mm"] = fabric.tile_size_mm;
  nlohmann::json yarns = nlohmann::json::array();
  for (const auto& y : fabric.yarns)
    yarns.push_back(y.name);
  j["yarns"] = yarns;
  j["sheen"] = {{"color", fabric.sheen.color}, {"roughness", fabric.sheen.roughness}};
  j["bake"] = bake_settings_json(fabric.bake);
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& in : fabric.inputs)
    inputs.push_back({{"role", in.role}, {"path", in.path}, {"xxh64", in.xxh64}});
  j["inputs"] = inputs;
  return j;
}

}  // namespace clothbake

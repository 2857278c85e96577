// Names of section types, element types and codecs (layout.hpp).
#include <cinttypes>
#include <cstdio>
#include <cstring>

#include "formats/reader/layout.hpp"

namespace clothbake::reader {
namespace {

struct SectionName {
  SectionType type;
  const char* name;
};

constexpr SectionName kSectionNames[] = {
    {SectionType::Metadata, "metadata"},
    {SectionType::FabricInfo, "fabric_info"},
    {SectionType::YarnMaterials, "yarn_materials"},
    {SectionType::HeightMap, "height"},
    {SectionType::TangentMap, "tangent"},
    {SectionType::NormalMap, "normal"},
    {SectionType::GapMap, "gap"},
    {SectionType::YarnIdMap, "yarn_id"},
    {SectionType::AlbedoMap, "albedo"},
    {SectionType::ParallaxTable, "parallax"},
    {SectionType::ParallaxSat, "parallax_sat"},
    {SectionType::ParallaxEntropy, "parallax_entropy"},
    {SectionType::VisibilityAsg, "visibility_asg"},
    {SectionType::AsgFitError, "asg_fit_error"},
    {SectionType::ClusterLabels, "cluster_labels"},
    {SectionType::ClusterMeanVisibility, "cluster_mean_visibility"},
    {SectionType::ClusterVisibilityBasis, "cluster_visibility_basis"},
    {SectionType::RadianceRawTables, "radiance_tables"},
    {SectionType::RadianceCompressedTables, "radiance_compressed"},
    {SectionType::BinMap, "bin_map"},
    {SectionType::ScenePlan, "scene_plan"},
};

}  // namespace

const char* section_type_name(SectionType type) noexcept {
  for (const auto& entry : kSectionNames)
    if (entry.type == type) return entry.name;
  return nullptr;
}

#ifndef CLOTHBAKE_SINGLE_FILE
bool section_type_from_name(const char* name, SectionType* out) noexcept {
  if (name == nullptr) return false;
  for (const auto& entry : kSectionNames)
    if (std::strcmp(entry.name, name) == 0) {
      *out = entry.type;
      return true;
    }
  return false;
}
#endif

const char* element_type_name(ElementType type) noexcept {
  switch (type) {
    case ElementType::Opaque:
      return "opaque";
    case ElementType::U8:
      return "u8";
    case ElementType::I8:
      return "i8";
    case ElementType::U16:
      return "u16";
    case ElementType::I16:
      return "i16";
    case ElementType::U32:
      return "u32";
    case ElementType::I32:
      return "i32";
    case ElementType::U64:
      return "u64";
    case ElementType::I64:
      return "i64";
    case ElementType::F16:
      return "f16";
    case ElementType::F32:
      return "f32";
    case ElementType::F64:
      return "f64";
  }
  return nullptr;
}

const char* codec_name(Codec codec) noexcept {
  switch (codec) {
    case Codec::Raw:
      return "raw";
    case Codec::Zstd:
      return "zstd";
  }
  return nullptr;
}

const char* describe_section(char* buf, std::size_t cap, uint32_t index, uint32_t type,
                             uint32_t instance) noexcept {
  const char* name = section_type_name(SectionType(type));
  if (name)
    std::snprintf(buf, cap, "section #%" PRIu32 " (%s, instance %" PRIu32 ")", index, name,
                  instance);
  else
    std::snprintf(buf, cap, "section #%" PRIu32 " (type 0x%04" PRIx32 ", instance %" PRIu32 ")",
                  index, type, instance);
  return buf;
}

}  // namespace clothbake::reader

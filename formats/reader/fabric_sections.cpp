#include "formats/reader/fabric_sections.hpp"

namespace clothbake::reader {
namespace {

// Finds a section of a type this reader interprets and checks its payload version.
Status find_known(const Asset& asset, SectionType type, SectionInfo* info) noexcept {
  Status status = asset.find(type, 0, info);
  if (!status.ok()) return status;
  const uint16_t known = known_section_version(type);
  if (info->version == 0 || info->version > known)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "%s section has payload version %u, this reader reads version %u%s",
                         section_type_name(type), unsigned(info->version), unsigned(known),
                         info->version > known ? " (update the reader)" : "");
  return {};
}

template <class T>
Status map_view(const Asset& asset, SectionType type, uint32_t channels, uint32_t* resolution,
                ArrayView<T>* out) noexcept {
  SectionInfo info;
  Status status = find_known(asset, type, &info);
  if (!status.ok()) return status;
  status = asset.view_of(info, out);
  if (!status.ok()) return status;
  const uint16_t rank = channels == 1 ? 2 : 3;
  if (out->rank != rank || out->dims[0] != out->dims[1] || (rank == 3 && out->dims[2] != channels))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "%s map has shape rank %u {%u, %u, %u}, expected {N, N%s}",
                         section_type_name(type), unsigned(out->rank), unsigned(out->dims[0]),
                         unsigned(out->dims[1]), unsigned(out->dims[2]),
                         channels == 1 ? "" : ", 3");
  if (*resolution == 0) *resolution = out->dims[0];
  if (out->dims[0] != *resolution)
    return Status::error(ErrorCode::Malformed, Check::MapResolution,
                         "%s map is %u x %u, the other maps are %u x %u", section_type_name(type),
                         unsigned(out->dims[0]), unsigned(out->dims[1]), unsigned(*resolution),
                         unsigned(*resolution));
  return {};
}

template <class Record>
Status record_view(const Asset& asset, SectionType type, ArrayView<Record>* out) noexcept {
  SectionInfo info;
  Status status = find_known(asset, type, &info);
  if (!status.ok()) return status;
  ArrayView<uint8_t> bytes;
  status = asset.view_of(info, &bytes);
  if (!status.ok()) return status;
  if (bytes.rank != 2 || bytes.dims[1] != sizeof(Record))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "%s section must be u8 {count, %zu}", section_type_name(type),
                         sizeof(Record));
  // Offsets are 64-aligned and the buffer 8-aligned, so records (alignment 8) are aligned.
  out->data = reinterpret_cast<const Record*>(bytes.data);
  out->size = bytes.dims[0];
  out->rank = 1;
  out->dims[0] = bytes.dims[0];
  return {};
}

}  // namespace

uint16_t known_section_version(SectionType type) noexcept {
  switch (type) {
    case SectionType::Metadata:
    case SectionType::FabricInfo:
    case SectionType::YarnMaterials:
    case SectionType::HeightMap:
    case SectionType::TangentMap:
    case SectionType::NormalMap:
    case SectionType::GapMap:
    case SectionType::YarnIdMap:
    case SectionType::AlbedoMap:
      return 1;
    default:
      return 0;
  }
}

Status read_feature_maps(const Asset& asset, FeatureMapsView* out) noexcept {
  FeatureMapsView maps;
  Status status;
  if (status.ok())
    status = map_view(asset, SectionType::HeightMap, 1, &maps.resolution, &maps.height);
  if (status.ok())
    status = map_view(asset, SectionType::TangentMap, 3, &maps.resolution, &maps.tangent);
  if (status.ok())
    status = map_view(asset, SectionType::NormalMap, 3, &maps.resolution, &maps.normal);
  if (status.ok()) status = map_view(asset, SectionType::GapMap, 1, &maps.resolution, &maps.gap);
  if (status.ok())
    status = map_view(asset, SectionType::YarnIdMap, 1, &maps.resolution, &maps.yarn_id);
  if (status.ok())
    status = map_view(asset, SectionType::AlbedoMap, 3, &maps.resolution, &maps.albedo);
  if (status.ok()) *out = maps;
  return status;
}

Status read_fabric_info(const Asset& asset, const FabricInfoRecord** out) noexcept {
  ArrayView<FabricInfoRecord> records;
  Status status = record_view(asset, SectionType::FabricInfo, &records);
  if (!status.ok()) return status;
  if (records.size != 1)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "fabric_info section holds %llu records, expected 1",
                         static_cast<unsigned long long>(records.size));
  *out = records.data;
  return {};
}

Status read_yarn_materials(const Asset& asset, ArrayView<YarnMaterialRecord>* out) noexcept {
  return record_view(asset, SectionType::YarnMaterials, out);
}

}  // namespace clothbake::reader

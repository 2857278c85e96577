#include "formats/reader/fabric_sections.hpp"

#include <cstring>
#include <new>

#include "formats/reader/map_encoding.hpp"
#include "formats/reader/map_entropy.hpp"

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

// A map's view after find_known: shape {N, N} (channels 1) or {N, N, channels}, one common N.
template <class T>
Status map_view(const Asset& asset, const SectionInfo& info, uint32_t channels,
                uint32_t* resolution, ArrayView<T>* out) noexcept {
  const SectionType type = info.type;
  Status status = asset.view_of(info, out);
  if (!status.ok()) return status;  // WrongType names the element types
  const uint16_t rank = channels == 1 ? 2 : 3;
  if (out->rank != rank || out->dims[0] != out->dims[1] || (rank == 3 && out->dims[2] != channels))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "%s map (payload version %u) has shape rank %u {%u, %u, %u}, expected "
                         "{N, N%s}",
                         section_type_name(type), unsigned(info.version), unsigned(out->rank),
                         unsigned(out->dims[0]), unsigned(out->dims[1]), unsigned(out->dims[2]),
                         channels == 1 ? "" : (channels == 2 ? ", 2" : ", 3"));
  if (*resolution == 0) *resolution = out->dims[0];
  if (out->dims[0] != *resolution)
    return Status::error(ErrorCode::Malformed, Check::MapResolution,
                         "%s map is %u x %u, the other maps are %u x %u", section_type_name(type),
                         unsigned(out->dims[0]), unsigned(out->dims[1]), unsigned(*resolution),
                         unsigned(*resolution));
  return {};
}

// One coded map (height, tangent, normal, gap, albedo): its header checked here, decoded later
// into the FeatureMaps' storage.
struct FloatMap {
  SectionType type{};
  uint32_t channels = 1;  // floats per texel
  ArrayView<float>* out = nullptr;
  SectionInfo info;
  uint32_t codes_per_texel = 0;  // 16-bit codes per texel
  ArrayView<uint8_t> coded;      // the entropy-coded payload
  MapEntropyHeader header;
};

uint32_t codes_per_texel(SectionType type) noexcept {
  switch (type) {
    case SectionType::TangentMap:
    case SectionType::NormalMap:
      return 2;
    case SectionType::AlbedoMap:
      return 3;
    default:
      return 1;
  }
}

Status check_float_map(const Asset& asset, FloatMap& m, uint32_t* resolution) noexcept {
  Status status = find_known(asset, m.type, &m.info);
  if (!status.ok()) return status;
  m.codes_per_texel = codes_per_texel(m.type);
  status = asset.view_of(m.info, &m.coded);
  if (status.ok() && m.coded.rank != 1)
    status = Status::error(ErrorCode::WrongType, Check::SectionLayout, "%s map must be u8 {bytes}",
                           section_type_name(m.type));
  if (status.ok())
    status = check_map_entropy(section_type_name(m.type), m.coded.data, m.coded.size,
                               m.codes_per_texel, &m.header);
  if (!status.ok()) return status;
  if (*resolution == 0) *resolution = m.header.resolution;
  if (m.header.resolution != *resolution)
    return Status::error(ErrorCode::Malformed, Check::MapResolution,
                         "%s map is %u x %u, the other maps are %u x %u", section_type_name(m.type),
                         unsigned(m.header.resolution), unsigned(m.header.resolution),
                         unsigned(*resolution), unsigned(*resolution));
  return {};
}

// Turns the decoded 16-bit codes of a map into floats at `dst` (texels * channels) and points
// m.out at them.
void decode_codes(FloatMap& m, const uint16_t* codes, uint32_t n, float* dst) noexcept {
  const uint64_t texels = uint64_t(n) * n, count = texels * m.channels;
  switch (m.type) {
    case SectionType::HeightMap:
      for (uint64_t i = 0; i < count; ++i)
        dst[i] = half_to_float(Half{codes[i]});
      break;
    case SectionType::TangentMap:
    case SectionType::NormalMap:
      for (uint64_t t = 0; t < texels; ++t) {
        int16_t pair[2];
        std::memcpy(pair, codes + 2 * t, 4);
        decode_octahedral(pair, dst + 3 * t);
      }
      break;
    default:
      for (uint64_t i = 0; i < count; ++i)
        dst[i] = unorm16_to_float(codes[i]);
      break;
  }
  ArrayView<float>& v = *m.out;
  v.data = dst;
  v.size = count;
  v.rank = m.channels == 1 ? 2 : 3;
  v.dims[0] = n;
  v.dims[1] = n;
  v.dims[2] = m.channels == 1 ? 0 : m.channels;
  v.dims[3] = 0;
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
    case SectionType::YarnIdMap:
      return 1;
    case SectionType::HeightMap:
    case SectionType::TangentMap:
    case SectionType::NormalMap:
    case SectionType::GapMap:
    case SectionType::AlbedoMap:
      return kFeatureMapVersion;
    default:
      return 0;
  }
}

Status read_feature_maps(const Asset& asset, FeatureMaps* out) noexcept {
  FeatureMaps maps;
  FloatMap floats[5];
  const SectionType types[5] = {SectionType::HeightMap, SectionType::TangentMap,
                                SectionType::NormalMap, SectionType::GapMap,
                                SectionType::AlbedoMap};
  ArrayView<float>* views[5] = {&maps.height, &maps.tangent, &maps.normal, &maps.gap, &maps.albedo};
  for (int i = 0; i < 5; ++i) {
    floats[i].type = types[i];
    floats[i].channels = i == 0 || i == 3 ? 1 : 3;
    floats[i].out = views[i];
  }
  Status status;
  for (int i = 0; i < 4 && status.ok(); ++i)
    status = check_float_map(asset, floats[i], &maps.resolution);
  SectionInfo yarn_info;
  if (status.ok()) status = find_known(asset, SectionType::YarnIdMap, &yarn_info);
  if (status.ok()) status = map_view(asset, yarn_info, 1, &maps.resolution, &maps.yarn_id);
  if (status.ok()) status = check_float_map(asset, floats[4], &maps.resolution);
  if (!status.ok()) return status;

  const uint32_t n = maps.resolution;
  const uint64_t texels = uint64_t(n) * n;
  uint64_t decoded = 0;
  for (const FloatMap& m : floats)
    decoded += texels * m.channels;
  // open() bounded every section by the file size, and a header's N is <= 16384 and equal to the
  // others': these sizes cannot overflow. The codes of one map (at most 3 per texel), one byte
  // plane and the rANS tables are scratch.
  const model::Allocator* allocator = asset.allocator();
  model::Buffer<uint16_t> codes;
  model::Buffer<uint8_t> plane;
  model::Buffer<ParallaxEntropyScratch> scratch;
  if (!maps.storage.allocate(decoded, allocator) || !codes.allocate(texels * 3, allocator) ||
      !plane.allocate(texels, allocator) || !scratch.allocate(1, allocator))
    return Status::error(ErrorCode::Unsupported, Check::ResourceLimit,
                         "feature maps: cannot allocate %llu bytes for the decoded maps",
                         static_cast<unsigned long long>(decoded * sizeof(float)));
  float* dst = maps.storage.get();
  for (FloatMap& m : floats) {
    status = decode_map_entropy(section_type_name(m.type), m.coded.data, m.coded.size, m.header,
                                codes.get(), plane.get(), scratch.get());
    if (!status.ok()) return status;
    decode_codes(m, codes.get(), n, dst);
    dst += texels * m.channels;
  }
  *out = std::move(maps);
  return {};
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

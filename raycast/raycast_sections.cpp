#include "raycast/raycast_sections.hpp"

#include <cstring>

#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"

namespace clothbake::raycast {
namespace {

// A typed-array section whose payload the caller fills in place (integer element types only: the
// writer's NaN check concerns floating-point payloads, and check_sections() verifies the shape).
formats::Section blank_section(reader::SectionType type, uint32_t instance,
                               reader::ElementType element, std::size_t element_size,
                               std::vector<uint32_t> dims) {
  formats::Section s;
  s.type = type;
  s.instance = instance;
  s.version = 1;
  s.element = element;
  std::size_t count = 1;
  for (uint32_t d : dims)
    count *= d;
  s.dims = std::move(dims);
  s.payload.resize(count * element_size);
  return s;
}

}  // namespace

std::vector<formats::Section> parallax_sections(ParallaxTable&& table) {
  const uint32_t n = uint32_t(table.resolution), d = uint32_t(table.dirs * table.dirs);
  reader::ParallaxInfoRecord info{};
  info.resolution = n;
  info.dirs = uint32_t(table.dirs);
  info.min_cos = table.min_cos;
  info.reference_height = table.reference_height;
  info.depth_scale = table.depth_scale;
  info.max_quantization_error = table.stats.max_quantization_error;
  info.max_offset = table.stats.max_sideways;
  std::vector<formats::Section> out;
  out.push_back(formats::make_record_section(
      reader::SectionType::ParallaxTable, reader::kParallaxInfoInstance,
      std::span<const reader::ParallaxInfoRecord>(&info, 1)));

  formats::Section codes =
      blank_section(reader::SectionType::ParallaxTable, reader::kParallaxCodesInstance,
                    reader::ElementType::U16, sizeof(uint16_t), {d, n, n});
  std::memcpy(codes.payload.data(), table.depth.data(), codes.payload.size());
  std::vector<uint16_t>().swap(table.depth);  // release the codes: the section holds them now

  formats::Section sat = blank_section(reader::SectionType::ParallaxSat, 0,
                                       reader::ElementType::U32, sizeof(uint32_t), {d, n, n});
  // The payload buffer comes from operator new (aligned for any fundamental type); the SAT is
  // written as uint32 values in host order, which the format requires to be little-endian.
  parallax_sat(reinterpret_cast<const uint16_t*>(codes.payload.data()), int(n), int(d),
               reinterpret_cast<uint32_t*>(sat.payload.data()));
  out.push_back(std::move(codes));
  out.push_back(std::move(sat));
  return out;
}

std::vector<formats::Section> visibility_sections(const VisibilityAsgs& asgs,
                                                  const VisibilitySettings& settings, int dirs,
                                                  bool fit_error_section) {
  const uint32_t n = uint32_t(asgs.resolution);
  reader::VisibilityInfoRecord info{};
  info.resolution = n;
  info.dirs = uint32_t(dirs);
  info.normal_offset_texels = settings.normal_offset_texels;
  info.max_bandwidth = model::kAsgMaxBandwidth;
  info.max_amplitude = model::kAsgMaxAmplitude;
  info.mean_fit_error = asgs.mean_fit_error;
  info.max_fit_error = asgs.max_fit_error;
  std::vector<formats::Section> out;
  out.push_back(formats::make_record_section(
      reader::SectionType::VisibilityAsg, reader::kVisibilityInfoInstance,
      std::span<const reader::VisibilityInfoRecord>(&info, 1)));
  std::vector<uint16_t> fields;
  fields.reserve(asgs.records.size() * reader::kAsgRecordFields);
  for (const model::AsgRecord& r : asgs.records)
    fields.insert(fields.end(), {r.axis_u, r.axis_v, r.rotation, r.lambda, r.mu, r.amplitude});
  out.push_back(formats::make_array_section<uint16_t>(reader::SectionType::VisibilityAsg,
                                                      reader::kVisibilityRecordsInstance, fields,
                                                      {n, n, reader::kAsgRecordFields}));
  if (fit_error_section)
    out.push_back(formats::make_array_section<float>(reader::SectionType::AsgFitError, 0,
                                                     asgs.fit_error, {n, n}));
  return out;
}

std::vector<model::AsgParams<float>> decoded_lobes(const VisibilityAsgs& asgs) {
  std::vector<model::AsgParams<float>> out;
  out.reserve(asgs.records.size());
  for (const model::AsgRecord& r : asgs.records)
    out.push_back(model::unpack_asg<float>(r));
  return out;
}

}  // namespace clothbake::raycast

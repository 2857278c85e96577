// Scene-planned asset sections (scene_plan_sections.hpp).
#include "formats/reader/scene_plan_sections.hpp"

#include <cmath>
#include <cstring>

namespace clothbake::reader {

Status read_bin_map(const Asset& asset, uint32_t instance, uint32_t expected,
                    BinMapView* out) noexcept {
  if (out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "bin_map: null output");
  *out = BinMapView{};
  SectionInfo info;
  Status s = asset.find(SectionType::BinMap, instance, &info);
  if (s.code() == ErrorCode::NotFound) return {};
  if (!s.ok()) return s;
  if (info.version != 1)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "bin_map instance %u: payload version %u is not 1", unsigned(instance),
                         unsigned(info.version));
  ArrayView<uint8_t> view;
  s = asset.view_of(info, &view);
  if (!s.ok()) return s;
  if (view.rank != 2 || view.dims[0] != view.dims[1] || view.dims[0] < 1 || view.dims[0] > 256 ||
      (expected != 0 && view.dims[0] != expected))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "bin_map instance %u must be u8 {n, n} with n in 1..256%s (the grid's "
                         "bins per side %u)",
                         unsigned(instance), expected ? " equal to the table's" : "",
                         unsigned(expected));
  const uint64_t bins = uint64_t(view.dims[0]) * view.dims[0];
  uint32_t kept = 0;
  for (uint64_t b = 0; b < bins; ++b) {
    if (view.data[b] > 1)
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "bin_map instance %u: bin %llu is %u (only 0 and 1 are defined)",
                           unsigned(instance), static_cast<unsigned long long>(b),
                           unsigned(view.data[b]));
    kept += view.data[b];
  }
  if (kept == 0)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "bin_map instance %u covers no bin", unsigned(instance));
  out->bins_per_side = uint32_t(view.dims[0]);
  out->mask = view.data;
  out->kept = kept;
  return {};
}

Status read_scene_plan(const Asset& asset, ScenePlanRecord* out, bool* present) noexcept {
  if (out == nullptr || present == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "scene_plan: null output");
  std::memset(out, 0, sizeof *out);
  *present = false;
  SectionInfo info;
  Status s = asset.find(SectionType::ScenePlan, 0, &info);
  if (s.code() == ErrorCode::NotFound) return {};
  if (!s.ok()) return s;
  if (info.version != 1)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "scene_plan: payload version %u is not 1", unsigned(info.version));
  ArrayView<uint8_t> view;
  s = asset.view_of(info, &view);
  if (!s.ok()) return s;
  if (view.rank != 2 || view.dims[0] != 1 || view.dims[1] != sizeof(ScenePlanRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "scene_plan must be u8 {1, 64} (one ScenePlanRecord)");
  ScenePlanRecord r;
  std::memcpy(&r, view.data, sizeof r);
  if ((r.flags & ~kPlanKnownFlags) != 0)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "scene_plan: flags 0x%x unknown to this reader (known: 0x%x)",
                         unsigned(r.flags), unsigned(kPlanKnownFlags));
  bool zero = r.reserved0 == 0;
  for (unsigned char b : r.reserved)
    zero = zero && b == 0;
  if (!(r.max_error > 0.0 && r.max_error <= 1.0) || !zero)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "scene_plan: max_error outside (0, 1] or non-zero reserved bytes");
  *out = r;
  *present = true;
  return {};
}

}  // namespace clothbake::reader

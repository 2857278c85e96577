// Per-texel ASG visibility sections: layout checks and queries (visibility_sections.hpp).
#include "formats/reader/visibility_sections.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "formats/reader/detail/open_sections.hpp"
#include "model/tile.hpp"

namespace clothbake::reader {

Status VisibilityAsgView::open(const Asset& asset) noexcept {
  *this = VisibilityAsgView();
  ArrayView<uint8_t> info_bytes;
  ArrayView<uint16_t> records;
  Status s = detail::view_required_pair(
      asset, {SectionType::VisibilityAsg, kVisibilityInfoInstance},
      {SectionType::VisibilityAsg, kVisibilityRecordsInstance},
      "this asset has no visibility ASGs (visibility_asg instances 0 and 1)",
      "visibility_asg: payload version must be 1 (this reader knows version 1)", &info_bytes,
      &records);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(VisibilityInfoRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "visibility_asg instance 0 must be u8 {1, 64} (one VisibilityInfoRecord)");
  VisibilityInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
  for (unsigned char b : info.reserved)
    if (b != 0)
      return Status::error(ErrorCode::Malformed, Check::Padding,
                           "visibility_asg: reserved bytes of the info record are not zero");
  if (info.resolution < 1 || info.resolution > kMaxVisibilityResolution || info.dirs < 1 ||
      info.dirs > 256)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "visibility_asg: resolution %u or directions %u out of range",
                         unsigned(info.resolution), unsigned(info.dirs));
  if (info.max_bandwidth != model::kAsgMaxBandwidth ||
      info.max_amplitude != model::kAsgMaxAmplitude)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "visibility_asg: record encoding (max bandwidth %g, max amplitude %g) "
                         "differs from this reader's (%g, %g)",
                         info.max_bandwidth, info.max_amplitude, model::kAsgMaxBandwidth,
                         model::kAsgMaxAmplitude);
  if (!(info.normal_offset_texels > 0.0 && info.normal_offset_texels <= 1.0) ||
      !(info.mean_fit_error >= 0.0 && info.mean_fit_error <= 2.0) ||
      !(info.max_fit_error >= 0.0 && info.max_fit_error <= 2.0))
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "visibility_asg: normal offset or fit error statistics out of range");
  const uint32_t n = info.resolution;
  if (records.rank != 3 || records.dims[0] != n || records.dims[1] != n ||
      records.dims[2] != kAsgRecordFields)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "visibility_asg instance 1 must be u16 {%u, %u, 6} (one AsgRecord per "
                         "texel)",
                         unsigned(n), unsigned(n));
  const float* fit_error = nullptr;
  ArrayView<float> errors;
  bool have_errors = false;
  s = detail::view_optional(asset, {SectionType::AsgFitError, 0},
                            "asg_fit_error: payload version must be 1", &errors, &have_errors);
  if (!s.ok()) return s;
  if (have_errors) {
    if (errors.rank != 2 || errors.dims[0] != n || errors.dims[1] != n)
      return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                           "asg_fit_error must be f32 {%u, %u}", unsigned(n), unsigned(n));
    for (uint64_t t = 0; t < errors.size; ++t)
      if (!(errors[t] >= 0.0f && errors[t] <= 2.0f))
        return Status::error(ErrorCode::Malformed, Check::ValueRange,
                             "asg_fit_error: texel (%llu, %llu) has error %g outside [0, 2]",
                             static_cast<unsigned long long>(t % n),
                             static_cast<unsigned long long>(t / n), double(errors[t]));
    fit_error = errors.data;
  }
  info_ = info;
  records_ = records.data;
  fit_error_ = fit_error;
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
model::AsgRecord VisibilityAsgView::record(int64_t x, int64_t y) const noexcept {
  const int64_t n = info_.resolution;
  return record_at(uint64_t(model::wrap_index(y, n)) * uint64_t(n) +
                   uint64_t(model::wrap_index(x, n)));
}
#endif

model::AsgRecord VisibilityAsgView::record_at(uint64_t t) const noexcept {
  const uint16_t* f = records_ + t * kAsgRecordFields;
  model::AsgRecord r;
  r.axis_u = f[0];
  r.axis_v = f[1];
  r.rotation = f[2];
  r.lambda = f[3];
  r.mu = f[4];
  r.amplitude = f[5];
  return r;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
model::AsgParams<double> VisibilityAsgView::lobe(int64_t x, int64_t y) const noexcept {
  return model::unpack_asg<double>(record(x, y));
}
#endif

model::AsgParams<double> VisibilityAsgView::lobe_at(uint64_t t) const noexcept {
  return model::unpack_asg<double>(record_at(t));
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
double VisibilityAsgView::fit_error(int64_t x, int64_t y) const noexcept {
  if (fit_error_ == nullptr) return std::numeric_limits<double>::quiet_NaN();
  const int64_t n = info_.resolution;
  return double(fit_error_[uint64_t(model::wrap_index(y, n)) * uint64_t(n) +
                           uint64_t(model::wrap_index(x, n))]);
}
#endif

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
Status VisibilityAsgView::visibility(int64_t x, int64_t y, const double w[3],
                                     double* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "visibility view is not open");
  if (w == nullptr || !std::isfinite(w[0]) || !std::isfinite(w[1]) || !std::isfinite(w[2]))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "light direction must have finite components");
  const double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (!(len > 0.0) || !std::isfinite(len))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "light direction must be non-zero");
  const model::Asg<double> g = model::asg_from_params(lobe(x, y));
  const double v = model::asg_eval(g, model::Vec3d(w[0] / len, w[1] / len, w[2] / len));
  *out = v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
  return {};
}
#endif

}  // namespace clothbake::reader

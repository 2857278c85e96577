// Per-texel ASG visibility sections: layout checks and queries (visibility_sections.hpp).
#include "formats/reader/visibility_sections.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace clothbake::reader {
namespace {

int64_t wrap(int64_t i, int64_t n) noexcept {
  int64_t r = i % n;
  return r < 0 ? r + n : r;
}

}  // namespace

Status VisibilityAsgView::open(const Asset& asset) noexcept {
  *this = VisibilityAsgView();
  SectionInfo info_s, records_s;
  Status s = asset.find(SectionType::VisibilityAsg, kVisibilityInfoInstance, &info_s);
  if (s.ok()) s = asset.find(SectionType::VisibilityAsg, kVisibilityRecordsInstance, &records_s);
  if (s.code() == ErrorCode::NotFound)
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "this asset has no visibility ASGs (visibility_asg instances 0 and 1)");
  if (!s.ok()) return s;
  if (info_s.version != 1 || records_s.version != 1)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "visibility_asg: payload version must be 1 (this reader knows version 1)");
  ArrayView<uint8_t> info_bytes;
  ArrayView<uint16_t> records;
  s = asset.view_of(info_s, &info_bytes);
  if (s.ok()) s = asset.view_of(records_s, &records);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(VisibilityInfoRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "visibility_asg instance 0 must be u8 {1, 64} (one VisibilityInfoRecord)");
  VisibilityInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
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
  SectionInfo error_s;
  const float* fit_error = nullptr;
  s = asset.find(SectionType::AsgFitError, 0, &error_s);
  if (s.ok()) {
    if (error_s.version != 1)
      return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                           "asg_fit_error: payload version must be 1");
    ArrayView<float> errors;
    s = asset.view_of(error_s, &errors);
    if (!s.ok()) return s;
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
  } else if (s.code() != ErrorCode::NotFound) {
    return s;
  }
  info_ = info;
  records_ = records.data;
  fit_error_ = fit_error;
  return {};
}

model::AsgRecord VisibilityAsgView::record(int64_t x, int64_t y) const noexcept {
  const int64_t n = info_.resolution;
  const uint16_t* f =
      records_ + (uint64_t(wrap(y, n)) * uint64_t(n) + uint64_t(wrap(x, n))) * kAsgRecordFields;
  model::AsgRecord r;
  r.axis_u = f[0];
  r.axis_v = f[1];
  r.rotation = f[2];
  r.lambda = f[3];
  r.mu = f[4];
  r.amplitude = f[5];
  return r;
}

model::AsgParams<double> VisibilityAsgView::lobe(int64_t x, int64_t y) const noexcept {
  return model::unpack_asg<double>(record(x, y));
}

double VisibilityAsgView::fit_error(int64_t x, int64_t y) const noexcept {
  if (fit_error_ == nullptr) return std::numeric_limits<double>::quiet_NaN();
  const int64_t n = info_.resolution;
  return double(fit_error_[uint64_t(wrap(y, n)) * uint64_t(n) + uint64_t(wrap(x, n))]);
}

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

}  // namespace clothbake::reader

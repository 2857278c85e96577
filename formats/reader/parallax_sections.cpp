// Parallax sections: layout checks and queries (parallax_sections.hpp).
#include "formats/reader/parallax_sections.hpp"

#include <cmath>
#include <cstring>

#include "formats/reader/detail/open_sections.hpp"
#include "model/directions.hpp"

namespace clothbake::reader {
namespace {

constexpr uint64_t kTwo32 = uint64_t(1) << 32;

int64_t wrap(int64_t i, int64_t n) noexcept {
  int64_t r = i % n;
  return r < 0 ? r + n : r;
}

}  // namespace

// The compressed form, decoded by open(): bin-major basis (bin b's K + 1 values contiguous) and
// the exclusive prefix sums of the coefficients, sat[(j * (N + 1) + i) * K + k] = sum of q_k over
// texels [0, i) x [0, j) (|sum| <= 32768 * 2^28 < 2^63: exact for any N).
struct ParallaxView::Packed {
  uint32_t n = 0, k = 0;
  std::unique_ptr<double[]> basis;        // D x (K + 1)
  std::unique_ptr<int64_t[]> sat;         // (N + 1)^2 x K
  const int16_t* coefficients = nullptr;  // N x N x K, in the asset
  uint64_t bytes = 0;
};

Status ParallaxView::open(const Asset& asset, ParallaxSource source) noexcept {
  *this = ParallaxView();
  Status s;
  if (source == ParallaxSource::Compressed) {
    s = open_compressed(asset);
  } else {
    s = open_raw(asset);
    if (source == ParallaxSource::Auto && s.code() == ErrorCode::NotFound) {
      SectionInfo unused;
      if (asset.find(SectionType::ParallaxCompressed, kCompressedParallaxInfoInstance, &unused)
              .ok() ||
          asset.find(SectionType::ParallaxCompressed, kCompressedParallaxBasisInstance, &unused)
              .ok() ||
          asset.find(SectionType::ParallaxCompressed, kCompressedParallaxCoeffsInstance, &unused)
              .ok())
        s = open_compressed(asset);
    }
  }
  if (!s.ok()) *this = ParallaxView();
  return s;
}

uint64_t ParallaxView::decoded_bytes() const noexcept {
  return packed_ ? packed_->bytes : 0;
}

Status ParallaxView::open_compressed(const Asset& asset) noexcept {
  ArrayView<uint8_t> info_bytes;
  ArrayView<float> basis;
  Status s = detail::view_required_pair(
      asset, {SectionType::ParallaxCompressed, kCompressedParallaxInfoInstance},
      {SectionType::ParallaxCompressed, kCompressedParallaxBasisInstance},
      "this asset has no compressed parallax table (parallax_compressed instances 0, 1 and 2)",
      "parallax_compressed: payload version must be 1 (this reader knows version 1)", &info_bytes,
      &basis);
  if (!s.ok()) return s;
  ArrayView<int16_t> coeffs;
  bool have_coeffs = false;
  s = detail::view_optional(
      asset, {SectionType::ParallaxCompressed, kCompressedParallaxCoeffsInstance},
      "parallax_compressed: payload version must be 1", &coeffs, &have_coeffs);
  if (!s.ok()) return s;
  if (!have_coeffs)
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "this asset has no compressed parallax table (parallax_compressed "
                         "instance 2, the coefficients, is missing)");
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(CompressedParallaxInfoRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax_compressed instance 0 must be u8 {1, 64} (one "
                         "CompressedParallaxInfoRecord)");
  CompressedParallaxInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
  if (info.flags != 0)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "parallax_compressed: flags %u unknown to this reader (version 1 has 0)",
                         unsigned(info.flags));
  if (info.resolution < 1 || info.resolution > kMaxParallaxResolution || info.dirs < 1 ||
      info.dirs > kMaxParallaxDirs || info.rank > kMaxParallaxRank)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax_compressed: resolution %u, directions %u or rank %u out of "
                         "range (1..%u, 1..%u, 0..%u)",
                         unsigned(info.resolution), unsigned(info.dirs), unsigned(info.rank),
                         unsigned(kMaxParallaxResolution), unsigned(kMaxParallaxDirs),
                         unsigned(kMaxParallaxRank));
  if (!(info.min_cos >= 0.0 && info.min_cos < 1.0) || !std::isfinite(info.reference_height) ||
      !(info.max_offset >= 0.0 && std::isfinite(info.max_offset)) ||
      !(info.rms_offset_error >= 0.0 && std::isfinite(info.rms_offset_error)) ||
      !(info.max_offset_error >= 0.0 && std::isfinite(info.max_offset_error)) ||
      !(info.max_depth_error >= 0.0 && std::isfinite(info.max_depth_error)))
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax_compressed: min_cos, reference height, max offset or an error "
                         "out of range");
  const uint64_t n = info.resolution, d = uint64_t(info.dirs) * info.dirs, k = info.rank;
  if (basis.rank != 2 || basis.dims[0] != k + 1 || basis.dims[1] != d)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax_compressed instance 1 must be f32 {%llu, %llu} (rank + 1, "
                         "directions)",
                         static_cast<unsigned long long>(k + 1),
                         static_cast<unsigned long long>(d));
  if (coeffs.rank != 3 || coeffs.dims[0] != n || coeffs.dims[1] != n || coeffs.dims[2] != k)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax_compressed instance 2 must be i16 {%llu, %llu, %llu} (N, N, "
                         "rank)",
                         static_cast<unsigned long long>(n), static_cast<unsigned long long>(n),
                         static_cast<unsigned long long>(k));
  for (uint64_t i = 0; i < basis.size; ++i)
    if (!std::isfinite(basis.data[i]))
      return Status::error(ErrorCode::Malformed, Check::NonFinite,
                           "parallax_compressed: basis value %llu (row %llu, direction %llu) is "
                           "not finite",
                           static_cast<unsigned long long>(i),
                           static_cast<unsigned long long>(i / d),
                           static_cast<unsigned long long>(i % d));
  const uint64_t sat_count = (n + 1) * (n + 1) * k;
  const uint64_t bytes = sat_count * 8 + d * (k + 1) * 8;
  if (bytes > kMaxParallaxDecodedBytes)
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "parallax_compressed: the decoded table would need %llu bytes (limit "
                         "%llu)",
                         static_cast<unsigned long long>(bytes),
                         static_cast<unsigned long long>(kMaxParallaxDecodedBytes));
  auto packed = std::shared_ptr<Packed>(new (std::nothrow) Packed);
  if (packed) {
    packed->basis.reset(new (std::nothrow) double[d * (k + 1)]);
    if (k) packed->sat.reset(new (std::nothrow) int64_t[sat_count]);
  }
  if (!packed || !packed->basis || (k && !packed->sat))
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "parallax_compressed: cannot allocate %llu bytes for the decoded table",
                         static_cast<unsigned long long>(bytes));
  packed->n = uint32_t(n);
  packed->k = uint32_t(k);
  packed->coefficients = coeffs.data;
  packed->bytes = bytes;
  for (uint64_t row = 0; row <= k; ++row)
    for (uint64_t b = 0; b < d; ++b)
      packed->basis[b * (k + 1) + row] = double(basis.data[row * d + b]);
  if (k) {
    int64_t* sat = packed->sat.get();
    const uint64_t stride = (n + 1) * k;
    std::memset(sat, 0, sizeof(int64_t) * stride);  // row j = 0
    for (uint64_t y = 0; y < n; ++y) {
      const int64_t* above = sat + y * stride;
      int64_t* row = sat + (y + 1) * stride;
      for (uint64_t c = 0; c < k; ++c)
        row[c] = 0;  // column i = 0
      const int16_t* q = coeffs.data + y * n * k;
      for (uint64_t x = 0; x < n; ++x)
        for (uint64_t c = 0; c < k; ++c)  // P(x+1, y+1) = q + P(x, y+1) + P(x+1, y) - P(x, y)
          row[(x + 1) * k + c] =
              int64_t(q[x * k + c]) + row[x * k + c] + above[(x + 1) * k + c] - above[x * k + c];
    }
  }
  info_ = ParallaxInfoRecord{};
  info_.resolution = info.resolution;
  info_.dirs = info.dirs;
  info_.min_cos = info.min_cos;
  info_.reference_height = info.reference_height;
  info_.depth_scale = 0.0;  // no codes
  info_.max_quantization_error = info.max_depth_error;
  info_.max_offset = info.max_offset;
  packed_info_ = info;
  packed_ = std::move(packed);
  return {};
}

Status ParallaxView::open_raw(const Asset& asset) noexcept {
  ArrayView<uint8_t> info_bytes;
  ArrayView<uint16_t> codes;
  Status s = detail::view_required_pair(
      asset, {SectionType::ParallaxTable, kParallaxInfoInstance},
      {SectionType::ParallaxTable, kParallaxCodesInstance},
      "this asset has no parallax table (parallax instances 0 and 1)",
      "parallax: payload version must be 1 (this reader knows version 1)", &info_bytes, &codes);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(ParallaxInfoRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax instance 0 must be u8 {1, 64} (one ParallaxInfoRecord)");
  ParallaxInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
  if (info.resolution < 1 || info.resolution > kMaxParallaxResolution || info.dirs < 1 ||
      info.dirs > kMaxParallaxDirs)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax: resolution %u or directions %u out of range (1..%u, 1..%u)",
                         unsigned(info.resolution), unsigned(info.dirs),
                         unsigned(kMaxParallaxResolution), unsigned(kMaxParallaxDirs));
  if (!(info.min_cos >= 0.0 && info.min_cos < 1.0) || !std::isfinite(info.reference_height) ||
      !(info.depth_scale >= 0.0 && std::isfinite(info.depth_scale)) ||
      !(info.max_quantization_error >= 0.0 && std::isfinite(info.max_quantization_error)) ||
      !(info.max_offset >= 0.0 && std::isfinite(info.max_offset)))
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax: min_cos, reference height, depth scale or error out of range");
  const uint64_t n = info.resolution, d = uint64_t(info.dirs) * info.dirs;
  if (codes.rank != 3 || codes.dims[0] != d || codes.dims[1] != n || codes.dims[2] != n)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax instance 1 must be u16 {%llu, %llu, %llu} (directions, N, N)",
                         static_cast<unsigned long long>(d), static_cast<unsigned long long>(n),
                         static_cast<unsigned long long>(n));
  const uint32_t* sat = nullptr;
  ArrayView<uint32_t> sat_view;
  bool have_sat = false;
  s = detail::view_optional(asset, {SectionType::ParallaxSat, 0},
                            "parallax_sat: payload version must be 1", &sat_view, &have_sat);
  if (!s.ok()) return s;
  if (have_sat) {
    if (sat_view.rank != 3 || sat_view.dims[0] != d || sat_view.dims[1] != n ||
        sat_view.dims[2] != n)
      return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                           "parallax_sat must be u32 with the parallax table's shape {%llu, %llu, "
                           "%llu}",
                           static_cast<unsigned long long>(d), static_cast<unsigned long long>(n),
                           static_cast<unsigned long long>(n));
    sat = sat_view.data;
  }
  info_ = info;
  codes_ = codes.data;
  sat_ = sat;
  return {};
}

double ParallaxView::bin_depth(uint32_t bin, int64_t x, int64_t y) const noexcept {
  const int64_t n = info_.resolution;
  if (packed_) {
    const uint32_t k = packed_->k;
    const double* b = packed_->basis.get() + uint64_t(bin) * (k + 1);
    const int16_t* q =
        packed_->coefficients + (uint64_t(wrap(y, n)) * uint64_t(n) + uint64_t(wrap(x, n))) * k;
    double r = b[0];
    for (uint32_t c = 0; c < k; ++c)
      r += double(q[c]) * b[c + 1];
    return r;
  }
  const uint64_t index =
      (uint64_t(bin) * uint64_t(n) + uint64_t(wrap(y, n))) * uint64_t(n) + uint64_t(wrap(x, n));
  return -double(codes_[index]) * info_.depth_scale;
}

Status ParallaxView::view_direction(const double view[3], double o[3]) const noexcept {
  if (view == nullptr || !std::isfinite(view[0]) || !std::isfinite(view[1]) ||
      !std::isfinite(view[2]))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "view direction must have finite components");
  const double len = std::sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
  if (!(len > 0.0) || !std::isfinite(len))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "view direction must be non-zero");
  o[0] = view[0] / len;
  o[1] = view[1] / len;
  o[2] = view[2] / len;
  if (o[2] < info_.min_cos) {  // onto the rim of the cap, same azimuth
    double planar = std::sqrt(o[0] * o[0] + o[1] * o[1]);
    double ax = planar > 0.0 ? o[0] / planar : 1.0, ay = planar > 0.0 ? o[1] / planar : 0.0;
    double s = std::sqrt(1.0 - info_.min_cos * info_.min_cos);
    o[0] = ax * s;
    o[1] = ay * s;
    o[2] = info_.min_cos;
  }
  return {};
}

double ParallaxView::weighted_depth(const int bin[4], const double weight[4], int64_t x,
                                    int64_t y) const noexcept {
  const uint64_t n = info_.resolution;
  const uint64_t texel = uint64_t(wrap(y, int64_t(n))) * n + uint64_t(wrap(x, int64_t(n)));
  if (packed_) {
    const uint32_t k = packed_->k;
    const double* rows[4];
    double w[4];
    int m = 0;
    for (int j = 0; j < 4; ++j)
      if (weight[j] > 0.0) {
        rows[m] = packed_->basis.get() + uint64_t(bin[j]) * (k + 1);
        w[m++] = weight[j];
      }
    for (int j = m; j < 4; ++j) {  // pad with zero weights on the first row
      rows[j] = m ? rows[0] : packed_->basis.get();
      w[j] = 0.0;
    }
    const int16_t* q = packed_->coefficients + texel * k;
    double r = w[0] * rows[0][0] + w[1] * rows[1][0] + w[2] * rows[2][0] + w[3] * rows[3][0];
    for (uint32_t c = 1; c <= k; ++c)
      r += double(q[c - 1]) *
           (w[0] * rows[0][c] + w[1] * rows[1][c] + w[2] * rows[2][c] + w[3] * rows[3][c]);
    return r;
  }
  double r = 0.0;
  for (int k = 0; k < 4; ++k)
    if (weight[k] > 0.0)
      r += weight[k] * (-double(codes_[uint64_t(bin[k]) * n * n + texel]) * info_.depth_scale);
  return r;
}

Status ParallaxView::depth(int64_t x, int64_t y, const double view[3],
                           ParallaxSample* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "parallax view is not open");
  double o[3];
  Status s = view_direction(view, o);
  if (!s.ok()) return s;
  const model::DirectionGrid<double> grid{int(info_.dirs), info_.min_cos};
  const model::BinBilinear<double> w = grid.bilinear(model::Vec3d(o[0], o[1], o[2]));
  double r = 0.0;
  for (int k = 0; k < 4; ++k)
    if (w.weight[k] > 0.0) r += w.weight[k] * bin_depth(uint32_t(w.index[k]), x, y);
  out->r = r;
  out->offset[0] = r / o[2] * o[0];
  out->offset[1] = r / o[2] * o[1];
  for (int i = 0; i < 3; ++i)
    out->direction[i] = o[i];
  return {};
}

uint64_t ParallaxView::code_prefix_sum(uint32_t bin, uint32_t x, uint32_t y) const noexcept {
  if (x == 0 || y == 0) return 0;
  const uint64_t n = info_.resolution;
  const uint32_t* table = sat_ + uint64_t(bin) * n * n;
  auto s = [&](uint64_t i, uint64_t j) -> uint32_t {  // exclusive prefix, modulo 2^32
    return (i == 0 || j == 0) ? 0u : table[(j - 1) * n + (i - 1)];
  };
  // A rectangle of x * rows texels sums to at most 65535 * x * rows: below 2^32 it is exact (the
  // common case, N <= 256, tested without a division).
  if (65535u * uint64_t(x) * y < kTwo32) return s(x, y);
  const uint64_t rows = (kTwo32 - 1) / (65535u * uint64_t(x));
  uint64_t sum = 0;
  for (uint64_t j0 = 0; j0 < y; j0 += rows) {
    const uint64_t j1 = j0 + rows < y ? j0 + rows : y;
    sum += uint32_t(s(x, j1) - s(x, j0));  // unsigned wrap-around gives the exact band sum
  }
  return sum;
}

// Integral of the (piecewise-constant) codes over [0, x) x [0, y), real 0 <= x, y <= N: bilinear
// between the exact integer prefix sums at the surrounding texel corners.
double ParallaxView::prefix_integral(uint32_t bin, double x, double y) const noexcept {
  const uint32_t n = info_.resolution;
  uint32_t i = uint32_t(x), j = uint32_t(y);
  if (i > n) i = n;
  if (j > n) j = n;
  const double fx = i < n ? x - double(i) : 0.0, fy = j < n ? y - double(j) : 0.0;
  const uint32_t i1 = i < n ? i + 1 : n, j1 = j < n ? j + 1 : n;
  const uint64_t e00 = code_prefix_sum(bin, i, j);
  double value = double(e00);
  if (fx > 0.0) value += fx * double(code_prefix_sum(bin, i1, j) - e00);
  if (fy > 0.0) value += fy * double(code_prefix_sum(bin, i, j1) - e00);
  if (fx > 0.0 && fy > 0.0) {
    // The texel (i, j) itself: its code times the covered fraction fx * fy.
    const uint64_t texel = (uint64_t(bin) * n + j) * n + i;
    value += fx * fy * double(codes_[texel]);
  }
  return value;
}

double ParallaxView::footprint_code_sum(uint32_t bin, const FootprintPlan& p) const noexcept {
  const double n = double(info_.resolution);
  auto in = [&](double x, double y) { return prefix_integral(bin, x, y); };
  double f = in(p.rx1, p.ry1) - in(p.x0, p.ry1) - in(p.rx1, p.y0) + in(p.x0, p.y0);
  if (p.qx > 0) f += p.qx * (in(n, p.ry1) - in(n, p.y0));
  if (p.qy > 0) f += p.qy * (in(p.rx1, n) - in(p.x0, n));
  if (p.qx > 0 && p.qy > 0) f += p.qx * p.qy * in(n, n);
  return f;
}

// The compressed footprint mean: the coefficient integrals W_k over the plan (the raw form's
// formula with K values at once; the integral of piecewise-constant q over [0, x) x [0, y) is
// exactly the bilinear interpolation of the integer prefix sums at the 4 surrounding corners),
// then r = sum_b w_b (B[0][b] + sum_k W_k / area B[k][b]).
double ParallaxView::packed_footprint(const FootprintPlan& p, const int bin[4],
                                      const double weight[4], double area) const noexcept {
  const Packed& pk = *packed_;
  const uint32_t k = pk.k, n = pk.n;
  double integral[kMaxParallaxRank];
  for (uint32_t c = 0; c < k; ++c)
    integral[c] = 0.0;
  const uint64_t stride = uint64_t(n + 1) * k;
  auto add = [&](double x, double y, double scale) {
    if (scale == 0.0) return;
    uint32_t i = uint32_t(x), j = uint32_t(y);
    if (i > n) i = n;
    if (j > n) j = n;
    const double fx = i < n ? x - double(i) : 0.0, fy = j < n ? y - double(j) : 0.0;
    const uint32_t i1 = i < n ? i + 1 : n, j1 = j < n ? j + 1 : n;
    const int64_t* p00 = pk.sat.get() + uint64_t(j) * stride + uint64_t(i) * k;
    const int64_t* p10 = pk.sat.get() + uint64_t(j) * stride + uint64_t(i1) * k;
    const int64_t* p01 = pk.sat.get() + uint64_t(j1) * stride + uint64_t(i) * k;
    const int64_t* p11 = pk.sat.get() + uint64_t(j1) * stride + uint64_t(i1) * k;
    const double w00 = scale * (1 - fx) * (1 - fy), w10 = scale * fx * (1 - fy),
                 w01 = scale * (1 - fx) * fy, w11 = scale * fx * fy;
    for (uint32_t c = 0; c < k; ++c)
      integral[c] +=
          w00 * double(p00[c]) + w10 * double(p10[c]) + w01 * double(p01[c]) + w11 * double(p11[c]);
  };
  const double nd = double(n);
  if (k) {
    add(p.rx1, p.ry1, 1.0);
    add(p.x0, p.ry1, -1.0);
    add(p.rx1, p.y0, -1.0);
    add(p.x0, p.y0, 1.0);
    if (p.qx > 0) {
      add(nd, p.ry1, p.qx);
      add(nd, p.y0, -p.qx);
    }
    if (p.qy > 0) {
      add(p.rx1, nd, p.qy);
      add(p.x0, nd, -p.qy);
    }
    if (p.qx > 0 && p.qy > 0) add(nd, nd, p.qx * p.qy);
  }
  double r = 0.0;
  for (int b = 0; b < 4; ++b) {
    if (!(weight[b] > 0.0)) continue;
    const double* row = pk.basis.get() + uint64_t(bin[b]) * (k + 1);
    double v = row[0] * area;
    for (uint32_t c = 0; c < k; ++c)
      v += integral[c] * row[c + 1];
    r += weight[b] * v;
  }
  return r / area;
}

Status ParallaxView::footprint_depth(const Footprint& rect, const double view[3],
                                     ParallaxSample* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "parallax view is not open");
  if (!has_sat())
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "this asset has no parallax_sat section (footprint queries need it)");
  // (The compressed form always answers footprints: its prefix sums are built by open().)
  FootprintPlan plan;
  Status s = plan_footprint(rect, info_.resolution, &plan);
  if (!s.ok()) return s;
  const double area = (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
  if (!(area > 0.0))
    return depth(int64_t(std::floor(rect.x0)), int64_t(std::floor(rect.y0)), view, out);
  double o[3];
  s = view_direction(view, o);
  if (!s.ok()) return s;
  const model::DirectionGrid<double> grid{int(info_.dirs), info_.min_cos};
  const model::BinBilinear<double> w = grid.bilinear(model::Vec3d(o[0], o[1], o[2]));
  double r;
  if (packed_) {
    r = packed_footprint(plan, w.index, w.weight, area);
  } else {
    double sum = 0.0;
    for (int k = 0; k < 4; ++k)
      if (w.weight[k] > 0.0) sum += w.weight[k] * footprint_code_sum(uint32_t(w.index[k]), plan);
    r = -sum * info_.depth_scale / area;
  }
  out->r = r;
  out->offset[0] = r / o[2] * o[0];
  out->offset[1] = r / o[2] * o[1];
  for (int i = 0; i < 3; ++i)
    out->direction[i] = o[i];
  return {};
}

}  // namespace clothbake::reader

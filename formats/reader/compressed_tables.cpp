// C-PCA compressed Integral-Radiance tables: validation, decoding into per-image SATs, footprint
// queries (compressed_tables.hpp).
#include "formats/reader/compressed_tables.hpp"

#include "formats/reader/compressed_coefficients.hpp"
#include "formats/reader/scene_plan_sections.hpp"

#include <cinttypes>
#include <cmath>
#include <cstring>
#include <new>
#include <type_traits>

namespace clothbake::reader {
namespace {

const char* kind_name(RadianceTableKind kind) noexcept {
  const char* name = radiance_kind_name(kind);
  return name ? name : "?";
}

Status layout_error(RadianceTableKind kind, const char* part, const char* detail) noexcept {
  return Status::error(ErrorCode::WrongType, Check::SectionLayout, "compressed_tables %s (%s): %s",
                       kind_name(kind), part, detail);
}

Status find_part(const Asset& asset, RadianceTableKind kind, CompressedPart part,
                 SectionInfo* out) noexcept {
  Status s =
      asset.find(SectionType::RadianceCompressedTables, compressed_instance(kind, part), out);
  if (s.code() == ErrorCode::NotFound)
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "compressed_tables: the %s tables are not in this asset (part %u missing)",
                         kind_name(kind), unsigned(part));
  if (!s.ok()) return s;
  if (out->version != 1)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "compressed_tables part %u: payload version %u is not 1", unsigned(part),
                         unsigned(out->version));
  return {};
}

bool half_is_finite(Half h) noexcept {
  return (h.bits & 0x7c00u) != 0x7c00u;
}

// `count` values (at least one, so that an empty table still tests true) from the asset's
// allocator; empty when the memory cannot be had.
template <class T>
model::Buffer<T> allocate(uint64_t count, const model::Allocator* allocator) noexcept {
  model::Buffer<T> buffer;
  if (count > SIZE_MAX || !buffer.allocate(count == 0 ? 1 : std::size_t(count), allocator))
    buffer.reset();
  return buffer;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // the SATs serve footprint queries, which the single file leaves out
// Builds the exclusive prefix sums S[j][i][k] (j, i in [0, N]) of the per-texel image weights.
template <class E>
void build_sats(uint32_t n, uint32_t images, const uint8_t* cell_map, const CompressedCell* cells,
                const int16_t* coefficients, E* sat, int64_t* row) noexcept {
  const uint64_t stride = uint64_t(n + 1) * images;
  std::memset(sat, 0, sizeof(E) * stride);  // row j = 0
  const int16_t* next = coefficients;
  for (uint32_t y = 0; y < n; ++y) {
    E* above = sat + uint64_t(y) * stride;
    E* here = above + stride;
    for (uint32_t k = 0; k < images; ++k)
      row[k] = 0;
    for (uint32_t k = 0; k < images; ++k)
      here[k] = 0;  // column i = 0
    for (uint32_t x = 0; x < n; ++x) {
      const uint8_t g = cell_map[uint64_t(y) * n + x];
      if (g != kNoCell) {
        const CompressedCell& cell = cells[g];
        row[cell.first_image] += 1;
        for (uint32_t j = 0; j < cell.rank; ++j)
          row[cell.first_image + 1 + j] += next[j];
        next += cell.rank;
      }
      const E* up = above + uint64_t(x + 1) * images;
      E* out = here + uint64_t(x + 1) * images;
      for (uint32_t k = 0; k < images; ++k)
        out[k] = E(up[k] + row[k]);
    }
  }
}
#endif

}  // namespace

Status CompressedRadianceTables::open(const Asset& asset, RadianceTableKind kind) noexcept {
  *this = CompressedRadianceTables();
  kind_ = kind;
  if (uint32_t(kind) >= kRadianceKindCount)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "unknown radiance table kind %u",
                         unsigned(kind));
  SectionInfo parts[kCompressedPartCount];
  for (uint32_t p = 0; p < kCompressedPartCount; ++p) {
    const Status s = find_part(asset, kind, CompressedPart(p), &parts[p]);
    if (!s.ok()) return s;
  }

  // Info.
  ArrayView<uint8_t> info_bytes;
  Status s = asset.view_of(parts[0], &info_bytes);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(CompressedTableInfoRecord))
    return layout_error(kind, "info", "must be u8 {1, 64}");
  CompressedTableInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
  if (info.kind != uint32_t(kind)) return layout_error(kind, "info", "kind field does not match");
  for (unsigned char b : info.reserved)
    if (b != 0)
      return Status::error(ErrorCode::Malformed, Check::Padding,
                           "compressed_tables %s (info): reserved bytes are not zero",
                           kind_name(kind));
  if ((info.flags & ~kCompressedPlannedFlag) != 0)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "compressed_tables %s (info): flags %u unknown to this reader (0 or 1)",
                         kind_name(kind), unsigned(info.flags));
  // A planned kind: the bins of bin_map instance 0 only (the gap kind has one bin: never planned).
  BinMapView bin_map;
  if ((info.flags & kCompressedPlannedFlag) != 0 && kind == RadianceTableKind::Gap)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "compressed_tables gap (info): the one-bin gap kind cannot be planned "
                         "(flags %u)",
                         unsigned(info.flags));
  if ((info.flags & kCompressedPlannedFlag) != 0) {
    s = read_bin_map(asset, kHalfVectorBinMap, 0, &bin_map);
    if (!s.ok()) return s;
    if (!bin_map.present())
      return Status::error(ErrorCode::NotFound, Check::MissingSection,
                           "compressed_tables %s: a planned kind needs bin_map instance 0 (the "
                           "half-vector bins it covers)",
                           kind_name(kind));
  }
  if (kind == RadianceTableKind::Gap && info.min_roughness != 0.0)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "compressed_tables gap (info): min_roughness %g must be 0",
                         info.min_roughness);
  if (info.resolution == 0 || info.resolution > kMaxRadianceResolution)
    return layout_error(kind, "info", "resolution out of range");
  if (info.bins_per_side == 0 || info.bins_per_side > kMaxRadianceBinsPerSide)
    return layout_error(kind, "info", "bins_per_side out of range");
  if (kind == RadianceTableKind::Gap && info.bins_per_side != 1)
    return layout_error(kind, "info", "the gap table has exactly one bin");
  if (bin_map.present() && kind != RadianceTableKind::Gap &&
      bin_map.bins_per_side != info.bins_per_side)
    return layout_error(kind, "info", "bins_per_side differs from bin_map instance 0");
  if (info.cluster_count == 0 || info.cluster_count > kMaxRadianceClusters)
    return layout_error(kind, "info", "cluster_count out of range");
  if (info.cell_count > kMaxCompressedCells)
    return layout_error(kind, "info", "cell_count out of range");
  if (info.image_count > kMaxCompressedImages)
    return layout_error(kind, "info", "image_count out of range");
  if (!std::isfinite(info.min_roughness) || !std::isfinite(info.bake_error))
    return Status::error(ErrorCode::Malformed, Check::NonFinite,
                         "compressed_tables %s (info): NaN or Inf field", kind_name(kind));
  const uint32_t n = info.resolution, cells_n = info.cell_count, images = info.image_count;
  const uint32_t bins = info.bins_per_side * info.bins_per_side;

  // Cells.
  ArrayView<uint32_t> cells_view;
  s = asset.view_of(parts[1], &cells_view);
  if (!s.ok()) return s;
  if (cells_n == 0 ? !(cells_view.rank == 2 && cells_view.dims[0] == 0)
                   : !(cells_view.rank == 2 && cells_view.dims[0] == cells_n &&
                       cells_view.dims[1] == kCellFields))
    return layout_error(kind, "cells", "must be u32 {cell_count, 4}");
  auto cells = allocate<CompressedCell>(cells_n ? cells_n : 1, asset.allocator());
  if (!cells) return Status::error(ErrorCode::Unsupported, Check::None, "out of memory");
  uint64_t image_total = 0, coefficient_total = 0;
  for (uint32_t g = 0; g < cells_n; ++g) {
    CompressedCell& c = cells[g];
    std::memcpy(&c, cells_view.data + uint64_t(g) * kCellFields, sizeof c);
    if (c.cluster >= info.cluster_count || (g > 0 && c.cluster < cells[g - 1].cluster) ||
        c.rank > kMaxCompressedRank || c.first_image != image_total || c.texels > uint64_t(n) * n ||
        c.rank > c.texels || c.rank > bins)
      return Status::error(
          ErrorCode::Malformed, Check::ValueRange,
          "compressed_tables %s: cell %u (cluster %u, rank %u, first image %u) "
          "is out of range or out of order (or its rank exceeds its texels or bins)",
          kind_name(kind), unsigned(g), unsigned(c.cluster), unsigned(c.rank),
          unsigned(c.first_image));
    image_total += 1 + uint64_t(c.rank);
    coefficient_total += uint64_t(c.texels) * c.rank;
  }
  if (image_total != images || coefficient_total != info.coefficient_count)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "compressed_tables %s: cells give %" PRIu64 " images and %" PRIu64
                         " coefficients, the info record says %u and %u",
                         kind_name(kind), image_total, coefficient_total, unsigned(images),
                         unsigned(info.coefficient_count));

  // Cell map.
  ArrayView<uint8_t> map;
  s = asset.view_of(parts[2], &map);
  if (!s.ok()) return s;
  if (map.rank != 2 || map.dims[0] != n || map.dims[1] != n)
    return layout_error(kind, "cell_map", "must be u8 {N, N}");
  {
    uint64_t counts[kMaxCompressedCells] = {};
    for (uint64_t t = 0; t < map.size; ++t) {
      const uint8_t g = map[t];
      if (g == kNoCell) continue;
      if (g >= cells_n)
        return Status::error(ErrorCode::Malformed, Check::ValueRange,
                             "compressed_tables %s: texel (%" PRIu64 ", %" PRIu64
                             ") names cell %u of %u",
                             kind_name(kind), t % n, t / n, unsigned(g), unsigned(cells_n));
      ++counts[g];
    }
    for (uint32_t g = 0; g < cells_n; ++g)
      if (counts[g] != cells[g].texels)
        return Status::error(ErrorCode::Malformed, Check::ValueRange,
                             "compressed_tables %s: cell %u has %" PRIu64
                             " texels in the map, %u in its record",
                             kind_name(kind), unsigned(g), counts[g], unsigned(cells[g].texels));
  }

  // Scales and basis.
  ArrayView<float> scales;
  s = asset.view_of(parts[3], &scales);
  if (!s.ok()) return s;
  if (scales.rank != 1 || scales.dims[0] != images)
    return layout_error(kind, "scales", "must be f32 {image_count}");
  for (uint32_t i = 0; i < images; ++i)
    if (!std::isfinite(scales[i]) || scales[i] < 0.0f)
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "compressed_tables %s: scale of image %u is not finite and >= 0",
                           kind_name(kind), unsigned(i));
  // A planned kind stores the columns of its covered bins only, in bin order (K of them); one
  // written before that rule stored all bins, the left-out ones zero: both are read.
  const bool planned_kind = bin_map.present() && kind != RadianceTableKind::Gap;
  uint32_t covered_bins = bins;
  if (planned_kind) {
    covered_bins = 0;
    for (uint32_t b = 0; b < bins; ++b)
      covered_bins += bin_map.mask[b] ? 1u : 0u;
  }
  ArrayView<Half> basis;
  s = asset.view_of(parts[4], &basis);
  if (!s.ok()) return s;
  if (basis.rank != 2 || basis.dims[0] != images ||
      (basis.dims[1] != bins && basis.dims[1] != covered_bins))
    return layout_error(kind, "basis",
                        planned_kind ? "must be f16 {image_count, covered bins of bin_map 0} (or "
                                       "{image_count, bins})"
                                     : "must be f16 {image_count, bins}");
  const uint64_t columns = basis.dims[1];
  for (uint64_t t = 0; t < basis.size; ++t) {
    if (!half_is_finite(basis[t]) || !(std::fabs(half_to_float(basis[t])) <= 1.0f))
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "compressed_tables %s: basis value of image %" PRIu64 " column %" PRIu64
                           " is not in [-1, 1]",
                           kind_name(kind), t / columns, t % columns);
  }

  // The decoded size is known from the shapes: refuse a huge one before decoding anything.
  const bool wide = uint64_t(n) > 256;  // N^2 * 32767 must stay below 2^31 for int32 sums
  const uint64_t sat_count = uint64_t(n + 1) * (n + 1) * (images ? images : 1);
  const uint64_t decoded = sat_count * (wide ? 8 : 4) + uint64_t(n) * n * sizeof(uint32_t);
  if (decoded > kMaxCompressedDecodedBytes)
    return Status::error(ErrorCode::Malformed, Check::ResourceLimit,
                         "compressed_tables %s: %u x %u texels with %u images decode to %" PRIu64
                         " bytes, more than the reader's limit of %" PRIu64,
                         kind_name(kind), unsigned(n), unsigned(n), unsigned(images), decoded,
                         kMaxCompressedDecodedBytes);

  // Coefficients: decoded into the copy the tables keep.
  const uint64_t texel_count = uint64_t(n) * n;
  auto coefficient_copy =
      allocate<int16_t>(info.coefficient_count ? info.coefficient_count : 1, asset.allocator());
  auto first_coefficient = allocate<uint32_t>(texel_count, asset.allocator());
  if (!coefficient_copy || !first_coefficient)
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "compressed_tables %s: cannot allocate the coefficients", kind_name(kind));
  {  // Each texel's first coefficient (the order: texel by texel, r_g values per texel with a
     // cell).
    uint64_t next = 0;
    for (uint64_t t = 0; t < texel_count; ++t) {
      first_coefficient[t] = uint32_t(next);
      const uint8_t g = map.data[t];
      if (g != kNoCell) next += cells[g].rank;
    }
  }
  ArrayView<int16_t> coefficients;
  {
    ArrayView<uint8_t> stream;
    s = asset.view_of(parts[5], &stream);
    if (!s.ok()) return s;
    if (stream.rank != 1) return layout_error(kind, "coefficients", "must be u8 {bytes}");
    model::Buffer<uint32_t> ranks = allocate<uint32_t>(cells_n ? cells_n : 1, asset.allocator());
    if (!ranks) return Status::error(ErrorCode::Unsupported, Check::None, "out of memory");
    for (uint32_t g = 0; g < cells_n; ++g)
      ranks[g] = cells[g].rank;
    s = decode_compressed_coefficients(stream.data, stream.dims[0], n, map.data, ranks.get(),
                                       first_coefficient.get(), info.coefficient_count,
                                       coefficient_copy.get());
    if (!s.ok())
      return Status::error(ErrorCode::Malformed, Check::ValueRange, "compressed_tables %s: %s",
                           kind_name(kind), s.message());
    coefficients.data = coefficient_copy.get();
    coefficients.size = info.coefficient_count;
    coefficients.rank = 1;
    coefficients.dims[0] = info.coefficient_count;
  }

  // Decode.
  model::Buffer<int32_t> sat32;
  model::Buffer<int64_t> sat64;
#ifndef CLOTHBAKE_SINGLE_FILE
  if (wide)
    sat64 = allocate<int64_t>(sat_count, asset.allocator());
  else
    sat32 = allocate<int32_t>(sat_count, asset.allocator());
  const bool sats_allocated = wide ? bool(sat64) : bool(sat32);
#else
  const bool sats_allocated = true;  // no SATs: the single file makes no footprint queries
#endif
  auto row = allocate<int64_t>(images ? images : 1, asset.allocator());
  auto scaled = allocate<float>(uint64_t(bins) * (images ? images : 1), asset.allocator());
  auto map_copy = allocate<uint8_t>(uint64_t(n) * n, asset.allocator());
  auto cell_cluster = allocate<uint32_t>(cells_n ? cells_n : 1, asset.allocator());
  auto cell_images = allocate<uint32_t>(2 * (cells_n ? cells_n : 1), asset.allocator());
  model::Buffer<uint8_t> covered;
  if (bin_map.present() && kind != RadianceTableKind::Gap) {
    covered = allocate<uint8_t>(bins, asset.allocator());
    if (covered) std::memcpy(covered.get(), bin_map.mask, bins);
  }
  if (!sats_allocated || !row || !scaled || !map_copy || !cell_cluster || !cell_images ||
      (bin_map.present() && kind != RadianceTableKind::Gap && !covered))
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "compressed_tables %s: cannot allocate %" PRIu64
                         " bytes for the decoded tables",
                         kind_name(kind), sat_count * (wide ? 8 : 4));
#ifndef CLOTHBAKE_SINGLE_FILE
  if (images > 0) {
    if (wide)
      build_sats(n, images, map.data, cells.get(), coefficients.data, sat64.get(), row.get());
    else
      build_sats(n, images, map.data, cells.get(), coefficients.data, sat32.get(), row.get());
  }
#endif
  for (uint32_t i = 0; i < images; ++i) {
    uint64_t column = 0;  // the stored column of bin b (compact planned form: covered bins only)
    for (uint32_t b = 0; b < bins; ++b) {
      const bool stored = columns == bins || bin_map.mask[b] != 0;
      scaled[uint64_t(b) * images + i] =
          stored ? scales[i] * half_to_float(basis[uint64_t(i) * columns + column]) : 0.0f;
      column += stored ? 1 : 0;
    }
  }
  std::memcpy(map_copy.get(), map.data, uint64_t(n) * n);
  for (uint32_t g = 0; g < cells_n; ++g) {
    cell_cluster[g] = cells[g].cluster;
    cell_images[2 * g] = cells[g].first_image;
    cell_images[2 * g + 1] = cells[g].rank;
  }
  info_ = info;
  n_ = n;
  bins_per_side_ = info.bins_per_side;
  cluster_count_ = info.cluster_count;
  images_ = images;
  wide_ = wide;
  sat32_ = std::move(sat32);
  sat64_ = std::move(sat64);
  basis_ = std::move(scaled);
  cell_map_ = std::move(map_copy);
  cell_cluster_ = std::move(cell_cluster);
  cell_images_ = std::move(cell_images);
  coefficients_ = std::move(coefficient_copy);
  first_coefficient_ = std::move(first_coefficient);
  covered_ = std::move(covered);
  // Cells are sorted by cluster: each cluster's images are one contiguous range.
  uint32_t g = 0;
  for (uint32_t c = 0; c <= cluster_count_; ++c) {
    while (g < cells_n && cells[g].cluster < c)
      ++g;
    image_begin_[c] = g < cells_n ? cells[g].first_image : images;
  }
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE
uint64_t CompressedRadianceTables::decoded_bytes() const noexcept {
  if (!is_open()) return 0;
  const uint64_t bins = uint64_t(bins_per_side_) * bins_per_side_;
  return uint64_t(n_ + 1) * (n_ + 1) * images_ * (wide_ ? 8 : 4) + bins * images_ * 4 +
         uint64_t(n_) * n_ * (1 + sizeof(uint32_t)) + uint64_t(info_.coefficient_count) * 2 +
         uint64_t(info_.cell_count) * 3 * sizeof(uint32_t);
}
#endif

int CompressedRadianceTables::cluster_of_texel(uint32_t x, uint32_t y) const noexcept {
  if (!is_open() || x >= n_ || y >= n_) return -1;
  const uint8_t g = cell_map_[uint64_t(y) * n_ + x];
  return g == kNoCell ? -1 : int(cell_cluster_[g]);
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
CompressedRadianceTables::TexelWeights CompressedRadianceTables::texel_weights(
    uint32_t x, uint32_t y) const noexcept {
  return texel_weights_at(uint64_t(y) * n_ + x);
}
#endif

CompressedRadianceTables::TexelWeights CompressedRadianceTables::texel_weights_at(
    uint64_t t) const noexcept {
  TexelWeights tw;
  const uint8_t g = cell_map_[t];
  if (g == kNoCell) return tw;
  tw.first_image = cell_images_[2 * g];
  tw.rank = int(cell_images_[2 * g + 1]);
  tw.q = coefficients_.get() + first_coefficient_[t];
  return tw;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
double CompressedRadianceTables::texel_value(uint32_t bin, uint32_t x, uint32_t y) const noexcept {
  if (!is_open() || x >= n_ || y >= n_ || bin >= bins_per_side_ * bins_per_side_) return 0.0;
  const TexelWeights tw = texel_weights(x, y);
  if (tw.rank < 0) return 0.0;
  double v = 0.0;
  const float* row = basis_.get() + uint64_t(bin) * images_ + tw.first_image;
  for (int j = 0; j <= tw.rank; ++j) {
    const int64_t w = tw.weight(j);
    if (w != 0) v += double(w) * double(row[j]);
  }
  return v;
}
#endif

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
double CompressedRadianceTables::texel_value(const BinWeights& weights, uint32_t x, uint32_t y,
                                             int* cluster) const noexcept {
  if (cluster != nullptr) *cluster = -1;
  const uint32_t bins = bins_per_side_ * bins_per_side_;
  if (!is_open() || x >= n_ || y >= n_ || weights.count > 4) return 0.0;
  for (uint32_t k = 0; k < weights.count; ++k)
    if (weights.bin[k] >= bins) return 0.0;
  const int c = cluster_of_texel(x, y);
  if (cluster != nullptr) *cluster = c;
  if (c < 0) return 0.0;
  const TexelWeights tw = texel_weights(x, y);
  double v = 0.0;
  for (int j = 0; j <= tw.rank; ++j) {
    const int64_t w = tw.weight(j);
    if (w == 0) continue;
    const uint32_t i = tw.first_image + uint32_t(j);
    double basis = 0.0;
    for (uint32_t k = 0; k < weights.count; ++k)
      basis += weights.weight[k] * double(basis_[uint64_t(weights.bin[k]) * images_ + i]);
    v += double(w) * basis;
  }
  return v;
}
#endif

uint32_t CompressedRadianceTables::texel_image_weights(uint32_t x, uint32_t y,
                                                       uint32_t* first_image,
                                                       double* weights) const noexcept {
  *first_image = 0;
  if (!is_open() || x >= n_ || y >= n_) return 0;
  return texel_image_weights_at(uint64_t(y) * n_ + x, first_image, weights);
}

uint32_t CompressedRadianceTables::texel_image_weights_at(uint64_t t, uint32_t* first_image,
                                                          double* weights) const noexcept {
  *first_image = 0;
  if (!is_open() || t >= uint64_t(n_) * n_) return 0;
  const TexelWeights tw = texel_weights_at(t);  // no division: this is the cheap samples' path
  if (tw.rank < 0) return 0;
  *first_image = tw.first_image;
  for (int j = 0; j <= tw.rank; ++j)
    weights[j] = double(tw.weight(j));
  return uint32_t(tw.rank + 1);
}

uint32_t CompressedRadianceTables::image_cluster(uint32_t image) const noexcept {
  uint32_t c = 0;
  while (c + 1 < cluster_count_ && image_begin_[c + 1] <= image)
    ++c;
  return c;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
int CompressedRadianceTables::decode_texel(uint32_t x, uint32_t y, float* out) const noexcept {
  if (!is_open() || out == nullptr || x >= n_ || y >= n_) return -1;
  const uint32_t bins = bins_per_side_ * bins_per_side_;
  const int c = cluster_of_texel(x, y);
  if (c < 0) {
    for (uint32_t b = 0; b < bins; ++b)
      out[b] = 0.0f;
    return -1;
  }
  const uint32_t first = image_begin_[c], last = image_begin_[c + 1];
  double w[kMaxCompressedImages];
  for (uint32_t i = first; i < last; ++i)
    w[i - first] = 0.0;
  const TexelWeights tw = texel_weights(x, y);
  for (int j = 0; j <= tw.rank; ++j)
    w[tw.first_image + uint32_t(j) - first] = double(tw.weight(j));
  for (uint32_t b = 0; b < bins; ++b) {
    const float* row = basis_.get() + uint64_t(b) * images_ + first;
    double v = 0.0;
    for (uint32_t i = 0; i < last - first; ++i)
      v += w[i] * double(row[i]);
    out[b] = float(v);
  }
  return c;
}
#endif

#ifndef CLOTHBAKE_SINGLE_FILE
template <class E>
bool CompressedRadianceTables::query_impl(const Footprint& rect, const double h[3], int cluster,
                                          double* out) const noexcept {
  FootprintPlan plan;
  BinWeights bw;
  if (!make_footprint_plan(rect, n_, &plan) || !make_bin_weights(bins_per_side_, h, &bw))
    return false;

  const uint32_t c_first = cluster < 0 ? 0 : uint32_t(cluster);
  const uint32_t c_end = cluster < 0 ? cluster_count_ : uint32_t(cluster) + 1;
  const uint32_t i0 = image_begin_[c_first], i1 = image_begin_[c_end];
  const uint32_t count = i1 - i0;
  double acc[kMaxCompressedImages];
  for (uint32_t k = 0; k < count; ++k)
    acc[k] = 0.0;

  // SAT points (x, y) in [0, N]^2 with their coefficients (FootprintPlan formula).
  const double size = double(n_);
  struct Point {
    double x, y, c;
  } points[9];
  int m = 0;
  points[m++] = {plan.rx1, plan.ry1, 1.0};
  points[m++] = {plan.x0, plan.ry1, -1.0};
  points[m++] = {plan.rx1, plan.y0, -1.0};
  points[m++] = {plan.x0, plan.y0, 1.0};
  if (plan.qx > 0) {
    points[m++] = {size, plan.ry1, plan.qx};
    points[m++] = {size, plan.y0, -plan.qx};
  }
  if (plan.qy > 0) {
    points[m++] = {plan.rx1, size, plan.qy};
    points[m++] = {plan.x0, size, -plan.qy};
  }
  if (plan.qx > 0 && plan.qy > 0) points[m++] = {size, size, plan.qx * plan.qy};

  const E* sat = static_cast<const E*>(wide_ ? static_cast<const void*>(sat64_.get())
                                             : static_cast<const void*>(sat32_.get()));
  const uint64_t stride = uint64_t(n_ + 1) * images_;
  // The 4 inner points (coefficients +-1, points 0..3 above) are combined in wrapping integer
  // arithmetic before anything is rounded: their S(i, j) corners sum to the rectangle sum over
  // integer corners; the first differences pair up into the partial column sums at x1 and x0 and
  // the partial row sums at y1 and y0 (each at most N * 32767 in magnitude, so exact in E), and the
  // second differences are the four corner texels. Only then is each integer multiplied by its
  // fractional coverage in double: sub-texel footprints keep double precision, and a cluster with
  // no texel (even partly) in the footprint gets exactly 0. Points of whole crossed tiles
  // (coefficients qx, qy, qx qy) are rare and use double throughout.
  using Wrap = std::conditional_t<sizeof(E) == 4, uint32_t, uint64_t>;
  using Signed = std::conditional_t<sizeof(E) == 4, int32_t, int64_t>;
  // Corner rows of every point first, then prefetch them all: a footprint's points are far apart
  // in the (N + 1)^2 x images SAT, so without this each point's 4 corner spans miss the cache one
  // after the other; issuing every line's load up front overlaps the misses (perf: the query was
  // bound by the loads of the corner differences).
  const E* corner[9];
  double fa[9], fb[9];
  for (int p = 0; p < m; ++p) {
    const uint32_t i = points[p].x >= size ? n_ - 1 : uint32_t(points[p].x);
    const uint32_t j = points[p].y >= size ? n_ - 1 : uint32_t(points[p].y);
    fa[p] = points[p].x - double(i);
    fb[p] = points[p].y - double(j);
    corner[p] = sat + uint64_t(j) * stride + uint64_t(i) * images_ + i0;
#if defined(__GNUC__)
    const std::size_t span = std::size_t(count) * sizeof(E);
    const char* rows[4] = {reinterpret_cast<const char*>(corner[p]),
                           reinterpret_cast<const char*>(corner[p] + images_),
                           reinterpret_cast<const char*>(corner[p] + stride),
                           reinterpret_cast<const char*>(corner[p] + stride + images_)};
    for (const char* row : rows)
      for (std::size_t off = 0; off < span; off += 64)
        __builtin_prefetch(row + off);
#endif
  }
  {
    // Points 0 (x1, y1, +), 1 (x0, y1, -), 2 (x1, y0, -), 3 (x0, y0, +): point 0 and 2 share the
    // column i1 and its fraction a1, 1 and 3 the column i0; 0 and 1 the row j1, 2 and 3 the row j0.
    const double a1 = fa[0], a0 = fa[1], b1 = fb[0], b0 = fb[2];
    const E* c0 = corner[0];
    const E* c1 = corner[1];
    const E* c2 = corner[2];
    const E* c3 = corner[3];
    auto d10 = [this](const E* s, uint32_t k) { return Wrap(s[k + images_]) - Wrap(s[k]); };
    auto d01 = [stride](const E* s, uint32_t k) { return Wrap(s[k + stride]) - Wrap(s[k]); };
    auto d11 = [this, stride](const E* s, uint32_t k) {
      return Wrap(s[k + stride + images_]) - Wrap(s[k + stride]) - Wrap(s[k + images_]) +
             Wrap(s[k]);
    };
    for (uint32_t k = 0; k < count; ++k) {
      const Wrap whole = Wrap(c0[k]) - Wrap(c1[k]) - Wrap(c2[k]) + Wrap(c3[k]);
      const Wrap column1 = d10(c0, k) - d10(c2, k), column0 = d10(c3, k) - d10(c1, k);
      const Wrap row1 = d01(c0, k) - d01(c1, k), row0 = d01(c3, k) - d01(c2, k);
      acc[k] += double(Signed(whole)) + a1 * double(Signed(column1)) +
                a0 * double(Signed(column0)) + b1 * double(Signed(row1)) +
                b0 * double(Signed(row0)) + a1 * b1 * double(Signed(d11(c0, k))) -
                a0 * b1 * double(Signed(d11(c1, k))) - a1 * b0 * double(Signed(d11(c2, k))) +
                a0 * b0 * double(Signed(d11(c3, k)));
    }
  }
  for (int p = 4; p < m; ++p) {
    const double a = fa[p], b = fb[p], c = points[p].c;
    const E* __restrict s00 = corner[p];
    const E* __restrict s10 = s00 + images_;
    const E* __restrict s01 = s00 + stride;
    const E* __restrict s11 = s01 + images_;
    const double w00 = (1 - a) * (1 - b) * c, w10 = a * (1 - b) * c, w01 = (1 - a) * b * c,
                 w11 = a * b * c;
    for (uint32_t k = 0; k < count; ++k)
      acc[k] +=
          w00 * double(s00[k]) + w10 * double(s10[k]) + w01 * double(s01[k]) + w11 * double(s11[k]);
  }

  // Directions: blend the (at most 4) bins' scaled basis rows first (elementwise, vectorisable),
  // then one dot product per cluster.
  double blend[kMaxCompressedImages];
  for (uint32_t k = 0; k < count; ++k)
    blend[k] = 0.0;
  for (uint32_t w = 0; w < bw.count; ++w) {
    const float* __restrict row = basis_.get() + uint64_t(bw.bin[w]) * images_ + i0;
    const double weight = bw.weight[w];
    for (uint32_t k = 0; k < count; ++k)
      blend[k] += weight * double(row[k]);
  }
  for (uint32_t c = c_first; c < c_end; ++c) {
    double total = 0.0;
    for (uint32_t k = image_begin_[c] - i0; k < image_begin_[c + 1] - i0; ++k)
      total += acc[k] * blend[k];
    out[c - c_first] = total;
  }
  return true;
}
#endif

bool CompressedRadianceTables::covers_bins(const double h[3]) const noexcept {
  if (!covered_) return true;
  BinWeights bw;
  if (!make_bin_weights(bins_per_side_, h, &bw)) return true;  // a bad h is InvalidArgument
  for (uint32_t k = 0; k < bw.count; ++k)
    if (bw.weight[k] > 0.0 && covered_[bw.bin[k]] == 0) return false;
  return true;
}

#ifndef CLOTHBAKE_SINGLE_FILE
bool CompressedRadianceTables::try_query(const Footprint& rect, const double h[3], uint32_t cluster,
                                         double* out) const noexcept {
  if (out == nullptr || !is_open() || cluster >= cluster_count_) return false;
  if (covered_ && !covers_bins(h)) return false;
  return wide_ ? query_impl<int64_t>(rect, h, int(cluster), out)
               : query_impl<int32_t>(rect, h, int(cluster), out);
}

bool CompressedRadianceTables::try_query_all(const Footprint& rect, const double h[3],
                                             double* out) const noexcept {
  if (out == nullptr || !is_open()) return false;
  if (covered_ && !covers_bins(h)) return false;
  return wide_ ? query_impl<int64_t>(rect, h, -1, out) : query_impl<int32_t>(rect, h, -1, out);
}
#else
// The single file builds no SATs: every footprint query fails (the unbiased multi-scale method,
// brute force and the reference make none).
bool CompressedRadianceTables::try_query(const Footprint&, const double[3], uint32_t,
                                         double*) const noexcept {
  return false;
}
bool CompressedRadianceTables::try_query_all(const Footprint&, const double[3],
                                             double*) const noexcept {
  return false;
}
#endif

}  // namespace clothbake::reader

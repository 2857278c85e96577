// C-PCA compressed Integral-Radiance tables of an asset (layout: compressed_layout.hpp), with the
// footprint queries of radiance_query.hpp: the same API as RawRadianceTables
// (formats/reader_raw/radiance_tables.hpp), so that a renderer
// does not care which one it has.
//
// Decoding. open() validates every section, then builds one exact integer summed-area table per
// image from the per-texel weights (the cell indicator and the quantised coefficients), laid out
// image-interleaved per SAT point, and the bin-major scaled basis (float). A query then reads,
// for each of the at most 9 SAT points of its footprint (4 when it does not cross a tile edge),
// the 4 surrounding integer corners of only the images of the clusters it asks for, and combines
// them with the at most 4 bilinear half-vector bins: nothing else is decompressed. Cost per query:
// O(images of the clusters asked for), independent of the footprint size.
//
// Memory: (N + 1)^2 * images * 4 bytes (8 when N > 256, where 32-bit prefix sums could overflow)
// plus bins * images * 4 bytes, plus a copy of the coefficients (2 bytes each) and each texel's
// first coefficient (N^2 * 4 bytes) for per-texel values, allocated once by open(); queries do not
// allocate.
//
// C++17, standard library only, noexcept. Safe on untrusted assets that Asset::open accepted:
// open() checks every shape, count, index and value range before anything is indexed. The Asset
// must outlive this object only during open() (everything needed afterwards is copied/decoded).
#pragma once

#include <cstdint>
#include <memory>

#include "formats/reader/asset.hpp"
#include "formats/reader/compressed_layout.hpp"
#include "formats/reader/radiance_query.hpp"

namespace clothbake::reader {

class CompressedRadianceTables final : public RadianceTables {
 public:
  CompressedRadianceTables() noexcept = default;
  CompressedRadianceTables(CompressedRadianceTables&&) noexcept = default;
  CompressedRadianceTables& operator=(CompressedRadianceTables&&) noexcept = default;

  // Opens kind's compressed tables. Errors: NotFound (CBK-E019: the kind has no compressed
  // tables, or a planned kind without bin_map instance 0), WrongType / Unsupported / Malformed
  // (CBK-E015: version, element type, shape, flags or record field), Malformed (CBK-E021: a
  // cluster id, rank, cell index, count, scale, basis value, or the coded coefficients out of
  // range; CBK-E017: NaN/Inf), Unsupported (the decoded tables cannot be allocated).
  Status open(const Asset& asset, RadianceTableKind kind) noexcept;
  bool is_open() const noexcept { return n_ != 0; }

  RadianceTableKind kind() const noexcept override { return kind_; }
  uint32_t resolution() const noexcept override { return n_; }
  uint32_t bins_per_side() const noexcept override { return bins_per_side_; }
  uint32_t cluster_count() const noexcept override { return cluster_count_; }
  bool try_query(const Footprint& rect, const double h[3], uint32_t cluster,
                 double* out) const noexcept override;
  bool try_query_all(const Footprint& rect, const double h[3], double* out) const noexcept override;
  // A scene-planned kind (info flags kCompressedPlannedFlag): false when a bin of h's bilinear
  // lookup (weight > 0) is outside bin_map instance 0; its queries then fail (query(): OutOfPlan).
  bool covers_bins(const double h[3]) const noexcept override;
  bool is_planned() const noexcept { return !covered_.empty(); }

  const CompressedTableInfoRecord& info() const noexcept { return info_; }
  uint32_t cell_count() const noexcept { return info_.cell_count; }
  uint32_t image_count() const noexcept { return images_; }
  // Whether cluster c (< cluster_count()) has any stored image (clusters without one answer 0).
  bool has_cluster(uint32_t c) const noexcept {
    return c < cluster_count_ && image_begin_[c + 1] > image_begin_[c];
  }
#ifndef CLOTHBAKE_SINGLE_FILE  // a report of the tools
  // Bytes of the decoded SATs and basis held in memory.
  uint64_t decoded_bytes() const noexcept;
#endif
  // Visibility cluster of texel (x, y) (x, y < N), or -1 when the texel has no cell (its value is 0
  // in every cluster).
  int cluster_of_texel(uint32_t x, uint32_t y) const noexcept;
  // Decompressed value of one texel in one bin (x, y < N, bin < bins): the table value T[c][bin]
  // of the texel's cluster c (0 when it has none).
  double texel_value(uint32_t bin, uint32_t x, uint32_t y) const noexcept;
  // The texel's value interpolated over the bins of `weights` (what a footprint query with the
  // same weights integrates; each image weight is read once), and its cluster (-1 without a cell,
  // value 0) in *cluster when not null. O(rank x bins of weights). x, y < N, weights from
  // make_bin_weights(bins_per_side(), ...); anything else gives 0 and cluster -1.
  double texel_value(const BinWeights& weights, uint32_t x, uint32_t y,
                     int* cluster) const noexcept;
  // The image weights of texel (x, y) (x, y < N): its images are first_image .. first_image + count
  // - 1 (count = rank + 1 of its cell; 0 for a texel without a cell), image first_image + j
  // weighted by weights[j] (1 for the cell mean, the stored coefficient for basis image j), so that
  // texel_value(w, x, y) = sum_j weights[j] sum_k w.weight[k] image_basis(first_image + j,
  // w.bin[k]). `weights` must hold kMaxCompressedRank + 1 values. Returns count.
  uint32_t texel_image_weights(uint32_t x, uint32_t y, uint32_t* first_image,
                               double* weights) const noexcept;
  // The same for texel index t = y N + x (t < N^2).
  uint32_t texel_image_weights_at(uint64_t t, uint32_t* first_image,
                                  double* weights) const noexcept;
  // The scaled basis value of image `image` (< image_count()) in bin `bin` (< bins): what the
  // queries multiply the image's footprint sum with.
  float image_basis(uint32_t image, uint32_t bin) const noexcept {
    return basis_[uint64_t(bin) * images_ + image];
  }
  // Every image's scaled basis value in bin `bin` (< bins): image_count() floats, image order
  // (image_basis(i, bin) = row[i]); valid while the tables are open.
  const float* image_basis_row(uint32_t bin) const noexcept {
    return basis_.get() + uint64_t(bin) * images_;
  }
  // The visibility cluster whose tables image `image` (< image_count()) belongs to.
  uint32_t image_cluster(uint32_t image) const noexcept;
#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
  // Every bin of one texel at once (out: bins floats, zeros for a texel without a cell); returns
  // the texel's cluster or -1. O(bins x (1 + rank)): for full decompression (verify, export).
  int decode_texel(uint32_t x, uint32_t y, float* out) const noexcept;
#endif

 private:
#ifndef CLOTHBAKE_SINGLE_FILE
  template <class E>
  bool query_impl(const Footprint& rect, const double h[3], int cluster,
                  double* out) const noexcept;
#endif
  // The image weights of texel (x, y) (x, y < N): images first_image .. first_image + rank of its
  // cell, weight 1 for the mean and the stored coefficient q_j for basis image j; rank -1 without
  // a cell. What the per-image SATs hold as differences, read directly.
  struct TexelWeights {
    uint32_t first_image = 0;
    int rank = -1;
    const int16_t* q = nullptr;
    int64_t weight(int j) const noexcept { return j == 0 ? 1 : int64_t(q[j - 1]); }
  };
  TexelWeights texel_weights(uint32_t x, uint32_t y) const noexcept;
  TexelWeights texel_weights_at(uint64_t t) const noexcept;  // t = y N + x < N^2

  CompressedTableInfoRecord info_{};
  RadianceTableKind kind_ = RadianceTableKind::Specular;
  uint32_t n_ = 0, bins_per_side_ = 0, cluster_count_ = 0, images_ = 0;
  bool wide_ = false;             // int64 SATs (N > 256)
  model::Buffer<int32_t> sat32_;  // (N + 1)^2 x images, exclusive prefix sums
  model::Buffer<int64_t> sat64_;
  model::Buffer<float> basis_;                 // bins x images: scale[i] * basis[i][b]
  model::Buffer<uint8_t> cell_map_;            // N x N
  model::Buffer<uint32_t> cell_cluster_;       // per cell
  model::Buffer<uint32_t> cell_images_;        // per cell: first_image, rank
  model::Buffer<int16_t> coefficients_;        // the stored coefficients (M)
  model::Buffer<uint32_t> first_coefficient_;  // N x N: index of the texel's first coefficient
  model::Buffer<uint8_t> covered_;             // planned: bins kept (1) or left out (0)
  // Images of cluster c: [image_begin_[c], image_begin_[c + 1]) (cells sorted by cluster).
  uint32_t image_begin_[kMaxRadianceClusters + 1] = {};
};

}  // namespace clothbake::reader

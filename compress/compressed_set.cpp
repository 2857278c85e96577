// C-PCA compression and quantisation of one table kind (compressed_set.hpp).
#include "compress/compressed_set.hpp"

#include "compress/coefficient_coding.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "compress/half_float.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress {
namespace {

using reader::CompressedPart;
using reader::SectionType;

constexpr double kCoefficientMax = 32767.0;

// Appends one image: `values` (bins) divided by max |value|, as halves; returns that maximum.
double append_image(const double* values, std::size_t bins, std::size_t stride,
                    std::vector<reader::Half>* basis) {
  double peak = 0.0;
  for (std::size_t b = 0; b < bins; ++b)
    peak = std::max(peak, std::fabs(values[b * stride]));
  for (std::size_t b = 0; b < bins; ++b)
    basis->push_back(float_to_half(peak > 0.0 ? float(values[b * stride] / peak) : 0.0f));
  return peak;
}

// Decodes one texel's vector exactly as the reader computes it (float products of the scaled
// basis, double accumulation). Shared by decompress_texels and the bake's error measurement,
// which decodes block by block instead of holding a second copy of the tables.
class TexelDecoder {
 public:
  explicit TexelDecoder(const CompressedTableSet& set) : set_(set) {
    const std::size_t n = set.info.resolution, texels = n * n;
    bins_ = std::size_t(set.info.bins_per_side) * set.info.bins_per_side;
    const std::size_t images = set.scales.size();
    if (set.cell_map.size() != texels || set.basis.size() != images * bins_)
      throw_internal_error("decompress_texels: inconsistent set");
    // Scaled basis, image-major, exactly as the reader computes it (float product).
    scaled_.resize(images * bins_);
    for (std::size_t i = 0; i < images; ++i)
      for (std::size_t b = 0; b < bins_; ++b)
        scaled_[i * bins_ + b] = set.scales[i] * reader::half_to_float(set.basis[i * bins_ + b]);
    offset_.assign(texels + 1, 0);
    for (std::size_t t = 0; t < texels; ++t) {
      const uint8_t g = set.cell_map[t];
      offset_[t + 1] = offset_[t] + (g == reader::kNoCell ? 0 : set.cells[g].rank);
    }
  }
  std::size_t bins() const { return bins_; }
  // Texel t's vector into out (bins floats; zeros for a texel without a cell); acc: bins doubles.
  void decode(std::size_t t, double* acc, float* out) const {
    const uint8_t g = set_.cell_map[t];
    if (g == reader::kNoCell) {
      std::fill(out, out + bins_, 0.0f);
      return;
    }
    const auto& cell = set_.cells[g];
    const float* mean = scaled_.data() + std::size_t(cell.first_image) * bins_;
    for (std::size_t b = 0; b < bins_; ++b)
      acc[b] = double(mean[b]);
    for (uint32_t j = 0; j < cell.rank; ++j) {
      const double w = set_.coefficients[offset_[t] + j];
      const float* v = scaled_.data() + std::size_t(cell.first_image + 1 + j) * bins_;
      for (std::size_t b = 0; b < bins_; ++b)
        acc[b] += w * double(v[b]);
    }
    for (std::size_t b = 0; b < bins_; ++b)
      out[b] = float(acc[b]);
  }

 private:
  const CompressedTableSet& set_;
  std::size_t bins_ = 0;
  std::vector<float> scaled_;
  std::vector<uint64_t> offset_;
};

}  // namespace

uint64_t CompressedTableSet::payload_bytes() const {
  const uint64_t coded =
      empty() ? 0
              : (coded_coefficients.empty() ? code_compressed_coefficients(*this).size()
                                            : coded_coefficients.size());
  return sizeof(info) + cells.size() * sizeof(reader::CompressedCell) + cell_map.size() +
         scales.size() * 4 + scales.size() * stored_columns() * 2 + coded;
}

uint64_t CompressedTableSet::stored_columns() const {
  const uint64_t bins = uint64_t(info.bins_per_side) * info.bins_per_side;
  if ((info.flags & reader::kCompressedPlannedFlag) == 0 || covered.size() != bins) return bins;
  return uint64_t(std::count(covered.begin(), covered.end(), uint8_t(1)));
}

CompressedTableSet compress_tables(const DirectionalTexels& data, const CpcaOptions& options,
                                   CompressionStats* stats) {
  const std::size_t texels = data.texels(), bins = std::size_t(data.bins());
  if (data.values.size() != texels * bins || data.cluster.size() != texels)
    throw_internal_error("compress: inconsistent directional data");
  if (data.resolution < 1 || data.resolution > int(reader::kMaxRadianceResolution))
    throw_input_error("compress: resolution " + std::to_string(data.resolution) +
                      " is out of range");
  check_finite_non_negative(data);

  const CpcaResult cpca = clustered_pca(data.values.data(), texels, bins, data.cluster, options);
  if (cpca.cells.size() > reader::kMaxCompressedCells - 1)
    throw_input_error("compress: " + std::to_string(cpca.cells.size()) +
                      " C-PCA cells exceed the format's 254; lower the C-PCA cluster count");

  CompressedTableSet set;
  set.cell_map.assign(texels, reader::kNoCell);
  std::vector<uint32_t> first_image(cpca.cells.size());
  uint64_t images = 0, coefficient_count = 0;
  for (std::size_t g = 0; g < cpca.cells.size(); ++g) {
    const auto& c = cpca.cells[g];
    first_image[g] = uint32_t(images);
    images += 1 + uint64_t(c.rank());
    coefficient_count += c.rows.size() * std::size_t(c.rank());
    for (uint32_t t : c.rows)
      set.cell_map[t] = uint8_t(g);
  }
  if (images > reader::kMaxCompressedImages)
    throw_input_error("compress: " + std::to_string(images) + " images exceed the format's " +
                      std::to_string(reader::kMaxCompressedImages) +
                      "; lower the C-PCA cluster count or rank");
  if (coefficient_count > 0xffffffffull)
    throw_input_error("compress: too many coefficients for one section; lower the rank");

  // Images: mean then basis vectors, per cell; coefficient steps per (cell, component).
  set.scales.reserve(images);
  set.basis.reserve(images * bins);
  std::vector<std::vector<double>> steps(cpca.cells.size());
  for (std::size_t g = 0; g < cpca.cells.size(); ++g) {
    const auto& c = cpca.cells[g];
    std::vector<double> mean(c.mean.begin(), c.mean.end());
    set.scales.push_back(float(append_image(mean.data(), bins, 1, &set.basis)));
    steps[g].resize(std::size_t(c.rank()));
    for (int j = 0; j < c.rank(); ++j) {
      const double peak = append_image(c.basis.col(j).data(), bins, 1, &set.basis);
      const double largest = double(c.coefficients.col(j).cwiseAbs().maxCoeff());
      const double step = largest > 0.0 ? largest / kCoefficientMax : 0.0;
      steps[g][std::size_t(j)] = step;
      set.scales.push_back(float(step * peak));
    }
    set.cells.push_back(
        {uint32_t(c.stratum), uint32_t(c.rank()), uint32_t(c.rows.size()), first_image[g]});
  }

  // Coefficients in texel order: position of each texel inside its cell's row list.
  std::vector<uint32_t> index_in_cell(texels, 0);
  for (const auto& c : cpca.cells)
    for (std::size_t i = 0; i < c.rows.size(); ++i)
      index_in_cell[c.rows[i]] = uint32_t(i);
  set.coefficients.reserve(coefficient_count);
  for (std::size_t t = 0; t < texels; ++t) {
    const uint8_t g = set.cell_map[t];
    if (g == reader::kNoCell) continue;
    const auto& c = cpca.cells[g];
    for (int j = 0; j < c.rank(); ++j) {
      const double step = steps[g][std::size_t(j)];
      const double v = step > 0.0 ? double(c.coefficients(index_in_cell[t], j)) / step : 0.0;
      set.coefficients.push_back(
          int16_t(std::clamp(std::nearbyint(v), -kCoefficientMax, kCoefficientMax)));
    }
  }

  auto& info = set.info;
  info = {};
  info.kind = uint32_t(data.kind);
  info.resolution = uint32_t(data.resolution);
  info.bins_per_side = uint32_t(data.bins_per_side);
  info.cluster_count = uint32_t(data.cluster_count);
  info.cell_count = uint32_t(set.cells.size());
  info.image_count = uint32_t(images);
  info.coefficient_count = uint32_t(coefficient_count);
  info.samples_per_bin_side = uint32_t(data.samples_per_bin_side);
  info.lobes = data.lobes;
  info.min_roughness = data.min_roughness;

  // Measure what is stored (the reader's arithmetic), decoding block by block.
  const TexelDecoder decoder(set);
  const std::size_t blocks = (texels + 1023) / 1024;
  std::vector<double> err2(blocks, 0.0), sig2(blocks, 0.0), max_err(blocks, 0.0),
      max_val(blocks, 0.0);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    std::vector<double> acc(bins);
    std::vector<float> decoded(bins);
    for (std::size_t t = b * 1024; t < std::min(texels, (b + 1) * 1024); ++t) {
      decoder.decode(t, acc.data(), decoded.data());
      for (std::size_t k = 0; k < bins; ++k) {
        const double x = data.values[t * bins + k], d = double(decoded[k]) - x;
        err2[b] += d * d;
        sig2[b] += x * x;
        max_err[b] = std::max(max_err[b], std::fabs(d));
        max_val[b] = std::max(max_val[b], x);
      }
    }
  });
  double e2 = 0.0, s2 = 0.0, me = 0.0, mv = 0.0;
  for (std::size_t b = 0; b < blocks; ++b) {
    e2 += err2[b];
    s2 += sig2[b];
    me = std::max(me, max_err[b]);
    mv = std::max(mv, max_val[b]);
  }
  info.bake_error = s2 > 0.0 ? std::sqrt(e2 / s2) : 0.0;
  if (!set.empty()) set.coded_coefficients = code_compressed_coefficients(set);

  if (stats) {
    *stats = {};
    stats->cpca_error = cpca.relative_error();
    stats->error = info.bake_error;
    stats->max_abs_error = me;
    stats->max_value = mv;
    stats->cells = int(set.cells.size());
    stats->images = int(images);
    stats->total_rank = cpca.total_rank();
    stats->min_rank = set.cells.empty() ? 0 : kMaxCpcaRank;
    for (const auto& c : set.cells) {
      stats->min_rank = std::min(stats->min_rank, int(c.rank));
      stats->max_rank = std::max(stats->max_rank, int(c.rank));
    }
    stats->iterations = cpca.iterations;
    std::vector<char> used(256, 0);
    for (uint8_t c : data.cluster)
      if (c != kNoStratum) used[c] = 1;
    for (char u : used)
      stats->stored_clusters += uint64_t(u);
    stats->raw_float_bytes = stats->stored_clusters * bins * texels * 4;
    stats->compressed_bytes = set.payload_bytes();
  }
  return set;
}

std::vector<float> decompress_texels(const CompressedTableSet& set) {
  const TexelDecoder decoder(set);
  const std::size_t texels = set.cell_map.size(), bins = decoder.bins();
  std::vector<float> out(texels * bins, 0.0f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, texels, 256), [&](const auto& range) {
    std::vector<double> acc(bins);
    for (std::size_t t = range.begin(); t != range.end(); ++t)
      decoder.decode(t, acc.data(), out.data() + t * bins);
  });
  return out;
}

std::vector<formats::Section> compressed_sections(const CompressedTableSet& set) {
  std::vector<formats::Section> out;
  if (set.empty()) return out;
  const auto kind = reader::RadianceTableKind(set.info.kind);
  const uint32_t n = set.info.resolution, images = set.info.image_count;
  const uint32_t bins = set.info.bins_per_side * set.info.bins_per_side;
  if (set.cells.size() != set.info.cell_count || set.scales.size() != images ||
      set.basis.size() != uint64_t(images) * bins || set.cell_map.size() != uint64_t(n) * n ||
      set.coefficients.size() != set.info.coefficient_count)
    throw_internal_error("compressed tables: inconsistent set");
  auto instance = [&](CompressedPart p) { return reader::compressed_instance(kind, p); };
  const reader::CompressedTableInfoRecord info = set.info;
  out.push_back(formats::make_record_section<reader::CompressedTableInfoRecord>(
      SectionType::RadianceCompressedTables, instance(CompressedPart::Info),
      std::span<const reader::CompressedTableInfoRecord>(&info, 1)));
  std::vector<uint32_t> cells;
  for (const auto& c : set.cells)
    cells.insert(cells.end(), {c.cluster, c.rank, c.texels, c.first_image});
  out.push_back(formats::make_array_section<uint32_t>(
      SectionType::RadianceCompressedTables, instance(CompressedPart::Cells), cells,
      {uint32_t(set.cells.size()), reader::kCellFields}));
  out.push_back(formats::make_array_section<uint8_t>(SectionType::RadianceCompressedTables,
                                                     instance(CompressedPart::CellMap),
                                                     set.cell_map, {n, n}));
  out.push_back(formats::make_array_section<float>(SectionType::RadianceCompressedTables,
                                                   instance(CompressedPart::Scales), set.scales,
                                                   {images}));
  // A planned kind: the covered bins' columns only (stored_columns()), image by image.
  const uint64_t columns = set.stored_columns();
  if (columns == bins) {
    out.push_back(formats::make_array_section<reader::Half>(SectionType::RadianceCompressedTables,
                                                            instance(CompressedPart::Basis),
                                                            set.basis, {images, bins}));
  } else {
    std::vector<reader::Half> compact;
    compact.reserve(uint64_t(images) * columns);
    for (uint64_t i = 0; i < images; ++i)
      for (uint32_t b = 0; b < bins; ++b)
        if (set.covered[b] == 1) compact.push_back(set.basis[i * bins + b]);
    out.push_back(formats::make_array_section<reader::Half>(SectionType::RadianceCompressedTables,
                                                            instance(CompressedPart::Basis),
                                                            compact, {images, uint32_t(columns)}));
  }
  const std::vector<uint8_t> coded =
      set.coded_coefficients.empty() ? code_compressed_coefficients(set) : set.coded_coefficients;
  out.push_back(formats::make_array_section<uint8_t>(SectionType::RadianceCompressedTables,
                                                     instance(CompressedPart::Coefficients), coded,
                                                     {uint32_t(coded.size())}));
  return out;
}

}  // namespace clothbake::compress

// Per-texel directional vectors of a table kind (directional_texels.hpp).
#include "compress/directional_texels.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "tables/half_vector_bins.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

namespace clothbake::compress {
namespace {

std::string texel_name(std::size_t t, int n) {
  return "texel (" + std::to_string(t % std::size_t(n)) + ", " +
         std::to_string(t / std::size_t(n)) + ")";
}

// The shape and provenance fields of a table set's info record; no texels yet.
DirectionalTexels empty_like(const reader::RadianceTableInfoRecord& info) {
  DirectionalTexels out;
  out.kind = reader::RadianceTableKind(info.kind);
  out.resolution = int(info.resolution);
  out.bins_per_side = int(info.bins_per_side);
  out.cluster_count = int(info.cluster_count);
  out.samples_per_bin_side = int(info.samples_per_bin_side);
  out.lobes = info.lobes;
  out.min_roughness = info.min_roughness;
  return out;
}

}  // namespace

void mark_zero_texels(DirectionalTexels* data) {
  const std::size_t texels = data->texels(), bins = std::size_t(data->bins());
  for (std::size_t t = 0; t < texels; ++t) {
    const float* row = data->row(t);
    bool zero = true;
    for (std::size_t b = 0; b < bins && zero; ++b)
      zero = row[b] == 0.0f;
    if (zero) data->cluster[t] = kNoStratum;
  }
}

void check_finite_non_negative(const DirectionalTexels& data) {
  const std::size_t texels = data.texels(), bins = std::size_t(data.bins());
  for (std::size_t t = 0; t < texels; ++t)
    for (std::size_t b = 0; b < bins; ++b) {
      const float v = data.row(t)[b];
      if (!std::isfinite(v) || v < 0.0f)
        throw_input_error("compress: " + std::string(reader::radiance_kind_name(data.kind)) +
                          " table value at " + texel_name(t, data.resolution) + " bin " +
                          std::to_string(b) + " is " + std::to_string(v) +
                          " (must be finite and >= 0)");
    }
}

DirectionalTexels directional_texels(const tables::RadianceSectionView& view,
                                     std::span<const uint8_t> labels) {
  if (!view.present()) throw_input_error("compress: the raw tables are not present");
  const auto& info = *view.info;
  DirectionalTexels out = empty_like(info);
  const std::size_t n = info.resolution, texels = n * n, bins = std::size_t(out.bins());
  const std::size_t columns = view.clusters.size();
  if (labels.size() != texels)
    throw_input_error("compress: the label map has " + std::to_string(labels.size()) +
                      " texels, the tables " + std::to_string(texels));
  std::vector<int> column_of(256, -1);
  for (std::size_t k = 0; k < columns; ++k)
    column_of[view.clusters[k]] = int(k);
  out.cluster.resize(texels);
  for (std::size_t t = 0; t < texels; ++t) {
    if (labels[t] >= info.cluster_count)
      throw_input_error("compress: label " + std::to_string(labels[t]) + " at " +
                        texel_name(t, int(n)) + " is not below the cluster count " +
                        std::to_string(info.cluster_count));
    out.cluster[t] = column_of[labels[t]] < 0 ? kNoStratum : labels[t];
  }
  out.values.assign(texels * bins, 0.0f);
  const bool wide = info.element_bits == 64;
  // value(b, x, y, k) = unit[b][k] * (S(x, y) - S(x-1, y) - S(x, y-1) + S(x-1, y-1)), inclusive
  // SAT, exact in wrapping uint64 arithmetic. Parallel over texel rows (disjoint outputs).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8), [&](const auto& range) {
    for (std::size_t y = range.begin(); y != range.end(); ++y)
      for (std::size_t b = 0; b < bins; ++b) {
        const std::size_t base = b * texels * columns;
        auto sat = [&](std::size_t x, std::size_t yy, std::size_t k) -> uint64_t {
          const std::size_t i = base + (yy * n + x) * columns + k;
          return wide ? reinterpret_cast<const uint64_t*>(view.sat)[i]
                      : reinterpret_cast<const uint32_t*>(view.sat)[i];
        };
        for (std::size_t x = 0; x < n; ++x) {
          const std::size_t t = y * n + x;
          if (out.cluster[t] == kNoStratum) continue;
          const std::size_t k = std::size_t(column_of[out.cluster[t]]);
          const uint64_t s11 = sat(x, y, k);
          const uint64_t s01 = x ? sat(x - 1, y, k) : 0;
          const uint64_t s10 = y ? sat(x, y - 1, k) : 0;
          const uint64_t s00 = x && y ? sat(x - 1, y - 1, k) : 0;
          const uint64_t q = s11 - s01 - s10 + s00;
          out.values[t * bins + b] = float(double(int64_t(q)) * view.units[b * columns + k]);
        }
      }
  });
  mark_zero_texels(&out);
  return out;
}

DirectionalTexels directional_texels(const tables::QuantisedRadianceFill& fill,
                                     std::span<const uint8_t> keep) {
  const auto& info = fill.header().info;
  DirectionalTexels out = empty_like(info);
  const std::size_t texels = out.texels(), bins = std::size_t(out.bins());
  const auto& columns = fill.columns();
  const auto& stored = fill.header().clusters;
  out.cluster.resize(texels);
  for (std::size_t t = 0; t < texels; ++t)
    out.cluster[t] = columns[t] < 0 ? kNoStratum : uint8_t(stored[std::size_t(columns[t])]);
  out.values.assign(texels * bins, 0.0f);
  // Blocks of 16 bins: one block writes 16 consecutive floats (a cache line) per texel.
  constexpr std::size_t kBlock = 16;
  const std::size_t blocks = (bins + kBlock - 1) / kBlock;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const auto& range) {
    std::vector<float> column(texels * kBlock);
    for (std::size_t block = range.begin(); block != range.end(); ++block) {
      const std::size_t b0 = block * kBlock, count = std::min(kBlock, bins - b0);
      for (std::size_t i = 0; i < count; ++i) {
        if (!keep.empty() && (b0 + i >= keep.size() || keep[b0 + i] == 0)) {
          std::fill_n(column.data() + i * texels, texels, 0.0f);  // left out by the plan
          continue;
        }
        fill.fill_bin(int(b0 + i), column.data() + i * texels);
      }
      for (std::size_t t = 0; t < texels; ++t) {
        float* row = out.values.data() + t * bins + b0;
        for (std::size_t i = 0; i < count; ++i)
          row[i] = column[i * texels + t];
      }
    }
  });
  mark_zero_texels(&out);
  return out;
}

DirectionalTexels directional_texels(reader::RadianceTableKind kind,
                                     const tables::RadianceInputs& inputs, int bins_per_side,
                                     int samples_per_bin_side) {
  tables::validate_radiance_inputs(inputs);
  DirectionalTexels out;
  out.kind = kind;
  out.resolution = inputs.resolution;
  out.cluster_count = inputs.cluster_count;
  const bool specular = kind == reader::RadianceTableKind::Specular;
  out.bins_per_side = specular ? bins_per_side : 1;
  out.min_roughness = specular ? tables::min_roughness_in_use(inputs) : 0.0;
  const int s = specular
                    ? (samples_per_bin_side > 0
                           ? samples_per_bin_side
                           : tables::default_samples_per_side(bins_per_side, out.min_roughness))
                    : 1;
  out.samples_per_bin_side = specular ? s : 0;
  out.lobes = specular ? (reader::kLobeBitSpecularReflection | reader::kLobeBitSpecularTransmission)
                       : reader::kLobeBitDeltaTransmission;
  const auto bins = tables::make_half_vector_bins(out.bins_per_side, s);
  const std::size_t texels = out.texels(), nb = std::size_t(out.bins());
  out.cluster.assign(inputs.labels.begin(), inputs.labels.end());
  out.values.assign(texels * nb, 0.0f);
  tbb::parallel_for(tbb::blocked_range<int>(0, out.bins(), 16), [&](const auto& range) {
    std::vector<float> column(texels);
    for (int b = range.begin(); b != range.end(); ++b) {
      tables::radiance_bin_values(kind, inputs, bins, b, column.data());
      for (std::size_t t = 0; t < texels; ++t)
        out.values[t * nb + std::size_t(b)] = column[t];
    }
  });
  mark_zero_texels(&out);
  return out;
}

}  // namespace clothbake::compress

// The data C-PCA compresses: one kind's Integral-Radiance tables seen as, per texel, a directional
// vector over the half-vector bins (docs/compression.md, "What the PCA vectors are").
//
// The raw layout (formats/reader/radiance_layout.hpp) stores, per visibility cluster c and bin b,
// the SAT of T[c][b](x) = V(x, b) [label(x) = c]: the clusters are masks of one texel x bin matrix
// V. Every texel's value lives in exactly one cluster's tables, so V plus the label map hold all
// the information of the C x B tables in B values per texel.
//
// C++20. Errors are clothbake::Error (Input) naming the offending texel or field.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "formats/reader/radiance_layout.hpp"

namespace clothbake::tables {
struct RadianceInputs;
struct RadianceSectionView;
class QuantisedRadianceFill;
}  // namespace clothbake::tables

namespace clothbake::compress {

inline constexpr uint8_t kNoStratum = 255;

struct DirectionalTexels {
  reader::RadianceTableKind kind = reader::RadianceTableKind::Specular;
  int resolution = 0;            // N
  int bins_per_side = 0;         // n (1 for Gap)
  int cluster_count = 0;         // visibility clusters of the label map
  int samples_per_bin_side = 0;  // quadrature of the raw tables (0 for Gap)
  uint32_t lobes = 0;            // reader::kLobeBit* answered by this kind
  double min_roughness = 0.0;
  // Per texel (row-major): the visibility cluster whose tables hold its values, or kNoStratum
  // when all of its values are 0 (it then contributes nothing to any table).
  std::vector<uint8_t> cluster;
  std::vector<float> values;  // texels x bins, row-major (texel t's vector at t * bins)

  int bins() const { return bins_per_side * bins_per_side; }
  std::size_t texels() const { return std::size_t(resolution) * std::size_t(resolution); }
  const float* row(std::size_t texel) const { return values.data() + texel * std::size_t(bins()); }
};

// From raw table sections (exact texel values recovered from the fixed-point SATs) and the label
// map the tables were built with (N x N, row-major). Errors (Input): labels of the wrong size or
// out of range, a view that is not present.
DirectionalTexels directional_texels(const tables::RadianceSectionView& view,
                                     std::span<const uint8_t> labels);

// Straight from the streaming fill (tables::QuantisedRadianceFill): bit-identical to
// directional_texels(view of the raw sets build_radiance_tables makes, their labels), without
// any SAT; peak memory is the returned vectors plus one 16-bin block per thread. Parallel over
// blocks of 16 bins (disjoint outputs): the same bytes for any thread count. A fill with no stored
// cluster gives every texel kNoStratum and zero values. `keep` (empty, or one entry per bin): the
// bins with keep[b] == 0 are not filled and stay 0 (a scene-planned bake, docs/scene-plans.md).
DirectionalTexels directional_texels(const tables::QuantisedRadianceFill& fill,
                                     std::span<const uint8_t> keep = {});

// Straight from the fill inputs (tables::radiance_bin_values with the default quadrature for
// `bins_per_side`): what the raw tables would hold before fixed-point quantisation. For tests,
// the report and verify (raw values recomputed from an asset's maps).
DirectionalTexels directional_texels(reader::RadianceTableKind kind,
                                     const tables::RadianceInputs& inputs, int bins_per_side,
                                     int samples_per_bin_side = 0);

// Sets cluster[t] = kNoStratum for texels whose vector is all zero (called by both builders).
void mark_zero_texels(DirectionalTexels* data);

// Throws Error(Input) naming the first texel and bin with a NaN, Inf or negative value.
void check_finite_non_negative(const DirectionalTexels& data);

}  // namespace clothbake::compress

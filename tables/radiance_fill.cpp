// Bin-averaged Integral-Radiance table fill with exact fixed-point SATs (radiance_fill.hpp).
#include "tables/radiance_fill.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "model/sggx.hpp"
#include "model/sggx_batch.hpp"
#include "tables/fixed_point_sat.hpp"

namespace clothbake::tables {
namespace {

// Texels per SoA block of the fill: 6 float arrays + accumulator stay in L2.
constexpr std::size_t kFillBlock = 2048;

std::string texel_name(std::size_t t, int n) {
  return "texel (" + std::to_string(t % std::size_t(n)) + ", " +
         std::to_string(t / std::size_t(n)) + ")";
}

// The fabric's SGGX constants in blocks of kFillBlock texels.
std::vector<model::FibreSggxBatch<float>> sggx_blocks(const RadianceInputs& in) {
  const std::size_t texels = std::size_t(in.resolution) * std::size_t(in.resolution);
  std::vector<model::FibreSggxBatch<float>> blocks((texels + kFillBlock - 1) / kFillBlock);
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const std::size_t begin = b * kFillBlock, end = std::min(texels, begin + kFillBlock);
    blocks[b].resize(end - begin);
    for (std::size_t t = begin; t < end; ++t) {
      const Vec3f& tg = in.tangent[t];
      const auto d = model::FibreSggx<float>::make(model::Vec3f(tg[0], tg[1], tg[2]),
                                                   float(in.roughness[in.yarn_id[t]]));
      blocks[b].set(t - begin, d);
    }
  }
  return blocks;
}

void specular_values(const std::vector<model::FibreSggxBatch<float>>& blocks,
                     std::span<const float> gap, const HalfVectorBins& bins, int bin, float* out) {
  const int per_bin = bins.samples_per_bin();
  const float weight = 1.0f / float(per_bin);
  std::size_t begin = 0;
  for (const auto& block : blocks) {
    float* acc = out + begin;
    std::fill(acc, acc + block.size(), 0.0f);
    for (int k = bin * per_bin; k < (bin + 1) * per_bin; ++k) {
      const model::Vec3f h(bins.x[std::size_t(k)], bins.y[std::size_t(k)], bins.z[std::size_t(k)]);
      model::sggx_d_over_texels_accumulate(block, h, weight, acc);
    }
    for (std::size_t t = 0; t < block.size(); ++t)
      acc[t] *= gap[begin + t];
    begin += block.size();
  }
}

void gap_values(const RadianceInputs& in, float* out) {
  const std::size_t texels = in.gap.size();
  for (std::size_t t = 0; t < texels; ++t)
    out[t] = 1.0f - in.gap[t];
}

// Clusters that get a table: those with a texel whose value can be non-zero.
std::vector<uint32_t> stored_clusters(const RadianceInputs& in, RadianceTableKind kind) {
  std::vector<char> used(std::size_t(in.cluster_count), 0);
  for (std::size_t t = 0; t < in.labels.size(); ++t) {
    const bool nonzero = kind == RadianceTableKind::Specular ? in.gap[t] > 0.0f : in.gap[t] < 1.0f;
    if (nonzero) used[in.labels[t]] = 1;
  }
  std::vector<uint32_t> out;
  for (int c = 0; c < in.cluster_count; ++c)
    if (used[std::size_t(c)]) out.push_back(uint32_t(c));
  return out;
}

// Per texel, the stored column of its cluster (index into set.clusters) or -1.
std::vector<int16_t> stored_columns(const RadianceInputs& in, const RadianceTableSet& set) {
  std::vector<int16_t> column_of(std::size_t(in.cluster_count), -1);
  for (std::size_t k = 0; k < set.clusters.size(); ++k)
    column_of[set.clusters[k]] = int16_t(k);
  std::vector<int16_t> column(in.labels.size());
  for (std::size_t t = 0; t < in.labels.size(); ++t)
    column[t] = column_of[in.labels[t]];
  return column;
}

// Per-column sums of one bin's values in texel order (double): the same order in the raw fill and
// the streaming fill, so both get the same scales.
void column_totals(std::span<const float> v, std::span<const int16_t> column,
                   std::span<double> totals) {
  std::fill(totals.begin(), totals.end(), 0.0);
  for (std::size_t t = 0; t < v.size(); ++t)
    if (column[t] >= 0) totals[std::size_t(column[t])] += double(v[t]);
}

// Fills the set for kind, bin by bin: values -> per-column totals -> fixed-point SAT.
template <class ValuesFn>
void fill_set(const RadianceInputs& in, RadianceTableSet& set, ValuesFn&& values) {
  const int n = in.resolution;
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  const std::size_t columns = set.clusters.size();
  const std::vector<int16_t> column = stored_columns(in, set);
  const int bins = set.bins();
  const std::size_t element = set.info.element_bits / 8;
  const std::size_t bin_bytes = texels * columns * element;
  set.units.assign(std::size_t(bins) * columns, 0.0);
  set.sat.resize(std::size_t(bins) * bin_bytes);
  tbb::parallel_for(tbb::blocked_range<int>(0, bins, 1), [&](const tbb::blocked_range<int>& r) {
    std::vector<float> v(texels);
    std::vector<double> totals(columns);
    for (int b = r.begin(); b != r.end(); ++b) {
      values(b, v.data());
      column_totals(v, column, totals);
      build_fixed_point_sat(n, v, column, totals, int(set.info.element_bits),
                            &set.units[std::size_t(b) * columns],
                            set.sat.data() + std::size_t(b) * bin_bytes);
    }
  });
}

RadianceTableSet empty_set(const RadianceInputs& in, RadianceTableKind kind, int bins_per_side,
                           const RadianceOptions& options) {
  RadianceTableSet set;
  std::memset(&set.info, 0, sizeof set.info);
  set.info.kind = uint32_t(kind);
  set.info.resolution = uint32_t(in.resolution);
  set.info.bins_per_side = uint32_t(bins_per_side);
  set.info.cluster_count = uint32_t(in.cluster_count);
  set.info.element_bits = uint32_t(sat_element_bits(in.resolution, options.max_relative_error));
  set.info.precision_target = options.max_relative_error;
  set.info.lobes = kind == RadianceTableKind::Specular
                       ? reader::kLobeBitSpecularReflection | reader::kLobeBitSpecularTransmission
                       : reader::kLobeBitDeltaTransmission;
  set.clusters = stored_clusters(in, kind);
  set.info.stored_clusters = uint32_t(set.clusters.size());
  return set;
}

void check_options(const RadianceOptions& o) {
  if (o.bins_per_side < 1 || o.bins_per_side > kMaxBinsPerSide)
    throw_input_error("radiance_dirs = " + std::to_string(o.bins_per_side) + " is outside [1, " +
                      std::to_string(kMaxBinsPerSide) + "]");
  if (o.samples_per_side < 0 || o.samples_per_side > kMaxSamplesPerBinSide)
    throw_input_error("samples per bin side = " + std::to_string(o.samples_per_side) +
                      " is outside [0, " + std::to_string(kMaxSamplesPerBinSide) + "]");
  if (!(o.max_relative_error > 0.0)) throw_input_error("the SAT precision target must be positive");
}

}  // namespace

uint64_t RadianceTableSet::sat_element(int bin, int x, int y, int column) const {
  const std::size_t n = std::size_t(resolution()), c = std::size_t(columns());
  const std::size_t index =
      ((std::size_t(bin) * n + std::size_t(y)) * n + std::size_t(x)) * c + std::size_t(column);
  if (info.element_bits == 32) {
    uint32_t v;
    std::memcpy(&v, sat.data() + index * 4, 4);
    return v;
  }
  uint64_t v;
  std::memcpy(&v, sat.data() + index * 8, 8);
  return v;
}

double RadianceTableSet::texel_value(int bin, int x, int y, int column) const {
  auto s = [&](int i, int j) -> uint64_t {
    return (i == 0 || j == 0) ? 0 : sat_element(bin, i - 1, j - 1, column);
  };
  const uint64_t q = s(x + 1, y + 1) - s(x, y + 1) - s(x + 1, y) + s(x, y);
  return double(int64_t(q)) *
         units[std::size_t(bin) * std::size_t(columns()) + std::size_t(column)];
}

FabricRadianceInputs radiance_inputs(const Fabric& fabric, std::span<const uint8_t> labels,
                                     int cluster_count) {
  FabricRadianceInputs out;
  for (const auto& yarn : fabric.yarns)
    out.roughness.push_back(yarn.roughness);
  out.view.resolution = fabric.maps.resolution;
  out.view.tangent = fabric.maps.tangent;
  out.view.gap = fabric.maps.gap;
  out.view.yarn_id = fabric.maps.yarn_id;
  out.view.roughness = out.roughness;
  out.view.labels = labels;
  out.view.cluster_count = cluster_count;
  return out;
}

void validate_radiance_inputs(const RadianceInputs& in) {
  const int n = in.resolution;
  if (n < 1 || n > int(reader::kMaxRadianceResolution))
    throw_input_error("radiance tables: resolution " + std::to_string(n) + " is outside [1, " +
                      std::to_string(reader::kMaxRadianceResolution) + "]");
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  if (in.tangent.size() != texels || in.gap.size() != texels || in.yarn_id.size() != texels ||
      in.labels.size() != texels)
    throw_input_error("radiance tables: the tangent, gap, yarn id and label maps must all have " +
                      std::to_string(texels) + " texels");
  if (in.cluster_count < 1 || in.cluster_count > int(reader::kMaxRadianceClusters))
    throw_input_error("radiance tables: cluster count " + std::to_string(in.cluster_count) +
                      " is outside [1, 255]");
  for (std::size_t y = 0; y < in.roughness.size(); ++y)
    if (!(in.roughness[y] > 0.0 && in.roughness[y] <= 1.0))
      throw_input_error("radiance tables: yarn " + std::to_string(y) + " roughness " +
                        std::to_string(in.roughness[y]) + " is outside (0, 1]");
  for (std::size_t t = 0; t < texels; ++t) {
    if (in.labels[t] >= in.cluster_count)
      throw_input_error("radiance tables: " + texel_name(t, n) + " has cluster label " +
                        std::to_string(in.labels[t]) + " >= " + std::to_string(in.cluster_count));
    if (in.yarn_id[t] >= in.roughness.size())
      throw_input_error("radiance tables: " + texel_name(t, n) + " has yarn id " +
                        std::to_string(in.yarn_id[t]) + " without a material");
    if (!(in.gap[t] >= 0.0f && in.gap[t] <= 1.0f))
      throw_input_error("radiance tables: " + texel_name(t, n) + " has gap " +
                        std::to_string(in.gap[t]) + " outside [0, 1]");
    const Vec3f& tg = in.tangent[t];
    if (!std::isfinite(tg[0]) || !std::isfinite(tg[1]) || !std::isfinite(tg[2]))
      throw_input_error("radiance tables: " + texel_name(t, n) + " has a non-finite tangent");
  }
}

double min_roughness_in_use(const RadianceInputs& in) {
  std::vector<char> used(in.roughness.size(), 0);
  for (uint16_t id : in.yarn_id)
    if (id < used.size()) used[id] = 1;
  double m = 1.0;
  for (std::size_t y = 0; y < used.size(); ++y)
    if (used[y]) m = std::min(m, in.roughness[y]);
  return m;
}

void radiance_bin_values(RadianceTableKind kind, const RadianceInputs& in,
                         const HalfVectorBins& bins, int bin, float* out) {
  if (kind == RadianceTableKind::Gap) {
    gap_values(in, out);
    return;
  }
  specular_values(sggx_blocks(in), in.gap, bins, bin, out);
}

namespace {

// The specular set's records and the report (quadrature, resolution warning), without the fill.
RadianceTableSet specular_header(const RadianceInputs& in, const RadianceOptions& options,
                                 RadianceBuildReport& rep) {
  check_options(options);
  validate_radiance_inputs(in);
  const double min_sigma = min_roughness_in_use(in);
  const int n = options.bins_per_side;
  const int s = options.samples_per_side > 0 ? options.samples_per_side
                                             : default_samples_per_side(n, min_sigma);
  rep.samples_per_side = s;
  rep.min_roughness = min_sigma;
  rep.bins_needed = bins_per_side_for_roughness(min_sigma);
  rep.resolved = bins_resolve_roughness(n, min_sigma);
  if (!rep.resolved) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "radiance tables: " << n << "^2 half-vector bins (" << bin_angular_width(n)
        << " rad wide) cannot resolve the narrowest lobe, roughness " << min_sigma
        << " (2-sigma rule: a bin must be at most " << 2 * min_sigma
        << " rad); radiance_dirs >= " << rep.bins_needed
        << " would resolve it. The tables still hold exact bin averages, but the bilinear lookup "
           "between bins blurs the highlight (clothbake verify reports the directional error)";
    rep.warnings.push_back(msg.str());
    if (options.warn_unresolved) warn(msg.str());
  }
  RadianceTableSet set = empty_set(in, RadianceTableKind::Specular, n, options);
  set.info.samples_per_bin_side = uint32_t(s);
  set.info.min_roughness = min_sigma;
  rep.element_bits = int(set.info.element_bits);
  rep.relative_error_bound = sat_relative_error_bound(in.resolution, rep.element_bits);
  if (!set.clusters.empty())
    rep.d_evaluations += uint64_t(in.resolution) * uint64_t(in.resolution) * uint64_t(set.bins()) *
                         uint64_t(s) * uint64_t(s);
  return set;
}

}  // namespace

RadianceTableSet build_specular_tables(const RadianceInputs& in, const RadianceOptions& options,
                                       RadianceBuildReport* report) {
  RadianceBuildReport local;
  RadianceTableSet set = specular_header(in, options, report ? *report : local);
  if (set.clusters.empty()) return set;
  const HalfVectorBins bins =
      make_half_vector_bins(options.bins_per_side, int(set.info.samples_per_bin_side));
  const auto blocks = sggx_blocks(in);
  fill_set(in, set, [&](int b, float* out) { specular_values(blocks, in.gap, bins, b, out); });
  return set;
}

RadianceTableSet build_gap_tables(const RadianceInputs& in, const RadianceOptions& options) {
  check_options(options);
  validate_radiance_inputs(in);
  RadianceTableSet set = empty_set(in, RadianceTableKind::Gap, 1, options);
  if (set.clusters.empty()) return set;
  fill_set(in, set, [&](int, float* out) { gap_values(in, out); });
  return set;
}

QuantisedRadianceFill::QuantisedRadianceFill(RadianceTableKind kind, const RadianceInputs& inputs,
                                             const RadianceOptions& options,
                                             RadianceBuildReport* report)
    : inputs_(inputs) {
  if (kind == RadianceTableKind::Specular) {
    RadianceBuildReport local;
    header_ = specular_header(inputs_, options, report ? *report : local);
    if (!header_.clusters.empty()) {
      quadrature_ =
          make_half_vector_bins(options.bins_per_side, int(header_.info.samples_per_bin_side));
      blocks_ = sggx_blocks(inputs_);
    }
  } else {
    check_options(options);
    validate_radiance_inputs(inputs_);
    header_ = empty_set(inputs_, RadianceTableKind::Gap, 1, options);
  }
  column_ = stored_columns(inputs_, header_);
}

void QuantisedRadianceFill::fill_bin(int bin, float* out) const {
  const std::size_t texels = column_.size(), columns = header_.clusters.size();
  if (columns == 0) {
    std::fill(out, out + texels, 0.0f);
    return;
  }
  if (header_.kind() == RadianceTableKind::Gap)
    gap_values(inputs_, out);
  else
    specular_values(blocks_, inputs_.gap, quadrature_, bin, out);
  std::vector<double> totals(columns), scales(columns), units(columns);
  column_totals(std::span<const float>(out, texels), column_, totals);
  fixed_point_scales(inputs_.resolution, totals, int(header_.info.element_bits), scales.data(),
                     units.data());
  for (std::size_t t = 0; t < texels; ++t) {
    const int k = column_[t];
    // Exactly what RadianceTableSet::texel_value gives back (then stored as float, as
    // compress::directional_texels does with the raw sets).
    out[t] = k < 0 ? 0.0f
                   : float(double(int64_t(fixed_point_quantise(out[t], scales[std::size_t(k)]))) *
                           units[std::size_t(k)]);
  }
}

std::vector<RadianceTableSet> build_radiance_tables(const RadianceInputs& inputs,
                                                    const RadianceOptions& options,
                                                    RadianceBuildReport* report) {
  std::vector<RadianceTableSet> out;
  RadianceTableSet specular = build_specular_tables(inputs, options, report);
  if (!specular.clusters.empty()) out.push_back(std::move(specular));
  RadianceTableSet gap = build_gap_tables(inputs, options);
  if (!gap.clusters.empty()) out.push_back(std::move(gap));
  return out;
}

}  // namespace clothbake::tables

// Integral-Radiance tables (paper Sec. 4.3, Eq. 11): the bin-averaged table fill and the exact
// fixed-point SATs, in memory, laid out exactly as the asset stores them
// (formats/reader/radiance_layout.hpp; docs/tables.md has the analysis of which tables exist).
//
//   Specular: T[c][b](x) = I(x) * (1/s^2) sum_k D_x(h_{b,k}) * [label(x) = c]   (bins n x n)
//   Gap:      T[c][0](x) = (1 - I(x)) * [label(x) = c]                         (one bin)
//
// D_x is the fibre-like SGGX distribution of texel x (its tangent, its yarn's roughness), h_{b,k}
// the s x s quadrature directions of half-vector bin b (half_vector_bins.hpp), evaluated with the
// model's batched SoA loop (model/sggx_batch.hpp) over blocks of texels. Work is split by bin over
// TBB; each bin's values, per-cluster totals (double, texel order) and SAT are computed by one
// task, so the tables are bit-identical for any thread count.
//
// C++20. Errors are clothbake::Error(Input) naming the offending texel or setting.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"
#include "formats/reader/radiance_layout.hpp"
#include "model/sggx_batch.hpp"
#include "tables/half_vector_bins.hpp"

namespace clothbake::tables {

using reader::RadianceTableKind;

// What the fill reads, per texel of the N x N tile (row-major). Views; not owned.
struct RadianceInputs {
  int resolution = 0;
  std::span<const Vec3f> tangent;     // fibre tangent (any length; normalised by the model)
  std::span<const float> gap;         // I(x) in [0, 1]
  std::span<const uint16_t> yarn_id;  // index into roughness
  std::span<const double> roughness;  // SGGX roughness per yarn, (0, 1]
  std::span<const uint8_t> labels;    // visibility cluster per texel, < cluster_count
  int cluster_count = 0;              // clusters of the label map, 1..255
};

// The inputs of a fabric and a label map (the fabric's yarn roughnesses, maps and labels).
struct FabricRadianceInputs {
  std::vector<double> roughness;
  RadianceInputs view;
};
FabricRadianceInputs radiance_inputs(const Fabric& fabric, std::span<const uint8_t> labels,
                                     int cluster_count);

struct RadianceOptions {
  int bins_per_side = 32;            // n: half-vector bins n x n (BakeSettings::radiance_dirs)
  int samples_per_side = 0;          // s; 0: default_samples_per_side(n, narrowest roughness)
  double max_relative_error = 1e-5;  // SAT precision target: picks u32 or u64 elements
  bool warn_unresolved = true;       // warn() when the bins cannot resolve the narrowest lobe
};

// One kind's tables, exactly the asset's four sections.
struct RadianceTableSet {
  reader::RadianceTableInfoRecord info{};  // every field set; reserved bytes zero
  std::vector<uint32_t> clusters;          // stored cluster ids, ascending
  std::vector<double> units;               // bins x clusters.size()
  std::vector<std::byte> sat;              // bins x N x N x clusters.size() elements

  RadianceTableKind kind() const { return RadianceTableKind(info.kind); }
  int resolution() const { return int(info.resolution); }
  int bins() const { return int(info.bins_per_side * info.bins_per_side); }
  int columns() const { return int(clusters.size()); }
  std::size_t element_count() const {
    return std::size_t(bins()) * std::size_t(resolution()) * std::size_t(resolution()) *
           std::size_t(columns());
  }
  // Inclusive SAT element [bin][y][x][column] (x, y < N).
  uint64_t sat_element(int bin, int x, int y, int column) const;
  // The texel's value recovered exactly from the SAT (quantised integer times unit).
  double texel_value(int bin, int x, int y, int column) const;
};

// Per-texel work counters and the quadrature used, for reports.
struct RadianceBuildReport {
  uint64_t d_evaluations = 0;  // SGGX D evaluations of the specular fill
  int samples_per_side = 0;
  double min_roughness = 0.0;
  int bins_needed = 0;   // 2-sigma rule for min_roughness
  bool resolved = true;  // bins_per_side >= bins_needed
  int element_bits = 32;
  double relative_error_bound = 0.0;
  std::vector<std::string> warnings;
};

// The specular table set (always produced when some texel has I(x) > 0; an empty `clusters` list
// otherwise: nothing to store). Errors: inputs of the wrong size, labels >= cluster_count, a yarn
// id without a roughness, roughness outside (0, 1], gap outside [0, 1] or a non-finite tangent or
// gap (naming the texel), options out of range.
RadianceTableSet build_specular_tables(const RadianceInputs& inputs, const RadianceOptions& options,
                                       RadianceBuildReport* report = nullptr);

// The gap table set (an empty `clusters` list when no texel has I(x) < 1).
RadianceTableSet build_gap_tables(const RadianceInputs& inputs, const RadianceOptions& options);

// Every table set the inputs need (the gap set only when some texel has I(x) < 1), kinds
// ascending.
std::vector<RadianceTableSet> build_radiance_tables(const RadianceInputs& inputs,
                                                    const RadianceOptions& options,
                                                    RadianceBuildReport* report = nullptr);

// The streaming form of a table set (docs/pipeline.md, "Streaming the tables into the
// compression"): per bin, the value every texel would read back from the raw fixed-point SAT,
// float(q * unit) with q = fixed_point_quantise(T(x), scale) and the bin's per-cluster scale, but
// without building (or holding) any SAT. A bake that keeps only the compressed tables feeds these
// values to the C-PCA bin by bin instead of materialising the raw sets (2 GiB for the twill); the
// compressed result is bit-identical to compressing the raw sets.
//
// Constructing it is cheap (checks the inputs, picks the quadrature and element width, builds
// the SoA blocks of the SGGX constants); the fill happens in fill_bin. Keeps references to
// `inputs`' spans: they must outlive the object. Errors as build_specular_tables.
class QuantisedRadianceFill {
 public:
  QuantisedRadianceFill(RadianceTableKind kind, const RadianceInputs& inputs,
                        const RadianceOptions& options, RadianceBuildReport* report = nullptr);

  // The set's records exactly as build_specular_tables / build_gap_tables make them (info,
  // stored clusters), with `units` and `sat` empty.
  const RadianceTableSet& header() const { return header_; }
  // No stored cluster: the raw builder would return an empty set (nothing to fill).
  bool empty() const { return header_.clusters.empty(); }
  int bins() const { return header_.bins(); }
  int resolution() const { return header_.resolution(); }
  // Bytes the raw SATs of this set would take (what the streaming form saves).
  std::size_t raw_sat_bytes() const {
    return header_.element_count() * std::size_t(header_.info.element_bits / 8);
  }
  // Per texel, row-major (N * N floats): the raw table's value of the texel in bin `bin` in the
  // column of its cluster (RadianceTableSet::texel_value, as float), 0 for a texel of no stored
  // cluster. Thread-safe (const); bins are independent.
  void fill_bin(int bin, float* out) const;
  // Per texel: the stored column (index into header().clusters) or -1.
  const std::vector<int16_t>& columns() const { return column_; }

 private:
  RadianceInputs inputs_;
  RadianceTableSet header_;
  std::vector<int16_t> column_;
  HalfVectorBins quadrature_;  // Specular only
  std::vector<model::FibreSggxBatch<float>> blocks_;
};

// The unquantised values T(x) of one bin for every texel (N * N floats, before the cluster mask):
// I(x) times the bin average of D_x for Specular, 1 - I(x) for Gap. What the SAT sums (up to
// quantisation); verify and tests use it for direct sums. `bins` must be the set's quadrature.
void radiance_bin_values(RadianceTableKind kind, const RadianceInputs& inputs,
                         const HalfVectorBins& bins, int bin, float* out);

// Checks inputs (throws as documented on build_specular_tables).
void validate_radiance_inputs(const RadianceInputs& inputs);

// Narrowest roughness among the yarns that occur in the map (1 if none).
double min_roughness_in_use(const RadianceInputs& inputs);

}  // namespace clothbake::tables

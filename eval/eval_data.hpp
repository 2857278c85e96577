// What an open Evaluator holds: the reader views of the asset, the per-yarn shading constants and
// the derived footprint sums; shared by the method implementations (eval/*.cpp). Internal to the
// evaluator library (not installed as API; its layout may change).
#pragma once

#include <cstdint>

#include "eval/cv_texels.hpp"
#include "eval/evaluator.hpp"
#ifndef CLOTHBAKE_SINGLE_FILE  // MultiscalePaper's sums: not in the single file
#include "eval/footprint_sums.hpp"
#endif
#include "eval/pushforward_sums.hpp"
#include "eval/subperiod_sums.hpp"
#include "formats/reader/cluster_sections.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#ifndef CLOTHBAKE_SINGLE_FILE  // the single file reads compressed tables only
#include "formats/reader_raw/radiance_tables.hpp"
#endif
#include "model/cloth_bsdf.hpp"

namespace clothbake::eval {

// The yarn record's Sec. 3 parameters as the BSDF takes them (the per-texel colour multiplies the
// three albedos, docs/evaluator.md "Texel parameters").
struct YarnShading {
  double roughness = 0.3;
  model::FibreSggx<double> sggx;  // its fibres' distribution (tangent +z): g_V sets the tangent
  double optical_thickness = 2.0;
  Rgb specular_albedo, diffuse_reflectance, diffuse_transmittance;
};

// One kind of Integral-Radiance tables, raw or compressed (exactly one of the two is open).
struct TableSource {
#ifndef CLOTHBAKE_SINGLE_FILE
  reader::RawRadianceTables raw;
#endif
  reader::CompressedRadianceTables compressed;
  const reader::RadianceTables* tables = nullptr;  // &raw or &compressed, null when absent

  bool present() const {
    return tables != nullptr;
  }
  bool is_compressed() const {
    return tables == &compressed;
  }
  // T(q, h) of texel (x, y) (x, y < N) interpolated over the bins of `weights`, and the cluster
  // whose table holds it (-1: none; the value is then 0). `label` is the texel's label-map cluster,
  // which is the raw tables' column (their columns hold a texel only under its label).
  double texel_value(const reader::BinWeights& weights, uint32_t x, uint32_t y, uint32_t label,
                     int* cluster) const noexcept;
};

struct EvalData {
  EvalOptions options;
  const model::Allocator* allocator = nullptr;  // of this object and every table below (not null)
  uint32_t n = 0;                               // resolution of every per-texel section
  reader::FeatureMaps maps;
  model::Buffer<YarnShading> yarns;
  model::Rgb<double> sheen_color;
  double sheen_roughness = 0.5;
  reader::ParallaxView parallax;
  reader::VisibilityAsgView visibility;
  reader::VisibilityClusterView clusters;
  // The clusters' visibility basis (not open for an asset without it, whose control variate then
  // has rank 0 with the stored cluster means).
  reader::VisibilityBasisView basis;
  TableSource specular, gap;
  // A scene-planned asset: what its bake left out (planned false: nothing).
  reader::ScenePlanRecord plan{};
  bool planned = false;
#ifndef CLOTHBAKE_SINGLE_FILE
  FootprintSums sums;  // multiscale-paper's footprint sums
#endif
  model::Buffer<Rgb> cluster_albedo;     // mean specular albedo k of each cluster's texels (tile)
  model::Buffer<uint32_t> cluster_yarn;  // the yarn of most of each cluster's texels
  // Per yarn, the parameters of its representative texel: the one whose fibre (tangent line and
  // roughness) is nearest the yarn's mean; the unbiased form evaluates Eq. 10's attenuation there
  // with the tangent turned normal to h.
  model::Buffer<model::TexelParams<double>> yarn_fibre;
  // Whether the tile has texels in gaps (I < 1) and on yarn (I > 0): importance sampling mixes
  // the techniques of both for a footprint with area only when both exist.
  bool has_gaps = false, has_yarn = false;
  model::Buffer<uint32_t> image_cluster;  // per compressed specular image: its cluster
  // Per cluster c: its compressed specular images are [cluster_image_begin[c], [c + 1]) (the
  // tables store them cluster by cluster); C + 1 entries.
  model::Buffer<uint32_t> cluster_image_begin;
  PushforwardSums pushforward;     // the unbiased form's whole-tile sums (pushforward_sums.hpp)
  SubperiodSums subperiod;         // its block sums (subperiod_sums.hpp; not open: no block form)
  ControlVariateTexels cv_texels;  // the unbiased form's per-texel records of g and g_V
                                   // (cv_texels.hpp)
  // Per band of the light's elevation |i_z| (kVisibilityBands bands of equal width): whether the
  // unbiased form's visibility correction runs there (visibility_pilot.cpp decides at open).
  static constexpr int kVisibilityBands = 4;
  // (Only the forms with a base correct: without one the control variate is g_V itself.)
  bool visibility_pays[kVisibilityBands] = {true, true, true, true};
  bool corrects_visibility(double cos_i) const {
    const int band = int(cos_i * kVisibilityBands);  // cos_i = |i_z| in [0, 1]
    return options.visibility_samples > 0 &&
           visibility_pays[band < kVisibilityBands ? band : kVisibilityBands - 1];
  }
  // Per band of min(|i_z|, |o_z|): whether g_V takes each texel's own specular attenuation rather
  // than its yarn's (EvalOptions::attenuation_pilot; visibility_pilot.cpp's run_attenuation_pilot
  // decides at open; the project's tests and studies may set it).
  static constexpr int kAttenuationBands = 4;
  bool attenuation_pays[kAttenuationBands] = {false, false, false, false};
  bool texel_attenuation(double min_cos) const {
    const int band = int(min_cos * kAttenuationBands);
    return attenuation_pays[band < kAttenuationBands ? band : kAttenuationBands - 1];
  }
  uint32_t visibility_rank() const {
    return basis.is_open() ? basis.rank() : 0;
  }
  // The texel offset per unit of depth of parallax view bin `bin` (Eq. 2 at the bin's centre
  // direction c: N (c_x, c_y) / c_z), or 0 without parallax (EvalOptions::parallax false).
  void bin_offset_per_depth(uint32_t bin, double out[2]) const;
  // e_0 = 1 and the texel's visibility basis coefficients e_1..e_M into e[0..M].
  void visibility_coefficients(uint64_t t, double* e) const {
    e[0] = 1.0;
    const uint32_t m = visibility_rank();
    if (m == 0) return;
    const float* c = basis.coefficients(t);
    for (uint32_t k = 0; k < m; ++k)
      e[k + 1] = c[k];
  }

  uint32_t cluster_count() const {
    return clusters.cluster_count();
  }
  uint64_t texel(int64_t x, int64_t y) const {
    if ((n & (n - 1)) == 0) {  // a power of two: the two's complement mask is the residue
      const uint64_t mask = uint64_t(n) - 1;
      return (uint64_t(y) & mask) * n + (uint64_t(x) & mask);
    }
    const int64_t nn = int64_t(n);
    int64_t xm = x % nn, ym = y % nn;
    if (xm < 0) xm += nn;
    if (ym < 0) ym += nn;
    return uint64_t(ym) * n + uint64_t(xm);
  }
  // The BSDF parameters of texel t (index y * N + x): its tangent and yarn, the colour times the
  // yarn's albedos, its gap value and the fabric's sheen.
  model::TexelParams<double> texel_params(uint64_t t) const;
};

// The evaluator's internal data (null when it is not open): for the project's tests and studies,
// which measure the estimator's parts; not part of the installed interface.
inline const EvalData* evaluator_data(const Evaluator& evaluator) noexcept {
  return evaluator.data_.get();
}

}  // namespace clothbake::eval

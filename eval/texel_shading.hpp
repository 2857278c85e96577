// The integrand of Eq. 5 at one texel, and the per-estimate constants every method shares
// (docs/evaluator.md, "The integrand").
//
//   g(t) = f^(t, i, o) V(t, i) |i_z|   per lobe of Eq. 4, the BSDF of model/cloth_bsdf.hpp with the
//                                      parameters of texel t (EvalData::texel_params)
//   delta: the weight V T_sheen (1 - I) of the Dirac term when i = -o, else 0
//
// Both sides of the cloth have the same relief (the model's two-sidedness): the parallax table is
// looked up for (o_x, o_y, |o_z|) and the visibility for (i_x, i_y, |i_z|).
//
// C++17, standard library only, no allocation. Internal to the evaluator library.
#pragma once

#include <cmath>
#include <cstdint>

#include "eval/eval_data.hpp"
#include "model/directions.hpp"

namespace clothbake::eval {

// Everything that depends on (i, o) but not on the texel, computed once per estimate.
struct ShadingFrame {
  model::Vec3d wi, wo;    // unit, as the caller gave them
  model::Vec3d wi_light;  // (i_x, i_y, |i_z|): the light direction of the visibility look-ups
  model::Vec3d view;      // the parallax direction as the table uses it (mirrored, on the cap)
  model::Vec3d h;         // i + o, unnormalised (D is homogeneous of degree 0)
  double cos_i = 0;       // |i_z|
  bool delta = false;     // i == -o exactly: the delta lobe contributes
  LobeMask mask = kAllLobes;
  // Eq. 2 in texel units for the view itself: r * offset_per_depth (multiscale-paper's shift).
  double offset_per_depth[2] = {0, 0};
  // Bilinear weights of the parallax view direction over the table's bins.
  model::BinBilinear<double> parallax_bins;
  // Eq. 2 in texel units at the centre direction of each of those four bins: a texel of depth
  // r_k in bin k moves by r_k * bin_offset_per_depth[k] (the model interpolates the results of
  // the four bins, docs/evaluator.md "The integral"). 0 without parallax.
  double bin_offset_per_depth[4][2] = {};
  // v_c(i) per cluster (Eq. 8), for the mirrored light direction.
  double mean_visibility[reader::kMaxVisibilityClusters];  // the first C entries are set
};

// v / |v| into *out; false for a null, non-finite or zero v.
bool unit_vector(const double v[3], model::Vec3d* out) noexcept;

// Builds the frame; false (with a message in *status) for a bad direction. wi, wo are normalised.
bool make_frame(const EvalData& data, const double wi[3], const double wo[3], LobeMask mask,
                ShadingFrame* frame, Status* status) noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
// The parallax depth r of texel (x, y) for the frame's view (bilinear between bins, as
// reader::ParallaxView::depth): what multiscale-paper's footprint mean approximates.
double texel_depth(const EvalData& data, const ShadingFrame& frame, int64_t x, int64_t y) noexcept;
#endif

#ifndef CLOTHBAKE_SINGLE_FILE  // MultiscalePaper's
// The diffuse albedo of texel index t for the diffuse lobe `lobe` (reflection: R_d, transmission:
// T_d): the yarn's times the texel's colour (docs/evaluator.md, "Texel parameters").
Rgb texel_diffuse_albedo(const EvalData& data, uint64_t t, model::Lobe lobe) noexcept;
#endif

// The lobes of frame.mask that a control variate carries for (i, o) and the specular lobe's
// half-vector bin weights: the specular and diffuse lobes of the reflection or transmission side
// (neither when i_z o_z = 0), the sheen, the delta lobe only at i = -o. h = 0 (i = -o) has no
// half-vector bin; the specular lobes are 0 there (D(0) = 0). Shared by both control-variate
// estimators; no allocation.
struct ActiveLobes {
  bool specular = false, diffuse = false, sheen = false, delta = false;
  model::Lobe specular_lobe = model::Lobe::SpecularReflection;
  model::Lobe diffuse_lobe = model::Lobe::DiffuseReflection;
  reader::BinWeights h_bins;
};
ActiveLobes active_lobes(const EvalData& data, const ShadingFrame& frame) noexcept;

// The view bin k in [0, 4) of frame.parallax_bins drawn with its weight by u in [0, 1): the first k
// whose cumulative weight exceeds u (the last with a positive weight if rounding leaves none).
int draw_view_bin(const ShadingFrame& frame, double u) noexcept;

// View bin k of a frame, ready for many destinations: its codes plane (null without parallax, for
// a bin that is not stored or whose plane cannot be allocated: r = 0), depth step and offset per
// unit depth. One per estimate; no allocation beyond the reader decoding the bin's plane once.
struct BinShift {
  const uint16_t* codes = nullptr;
  double step = 0.0;
  double offset_per_depth[2] = {0.0, 0.0};
};
BinShift bin_shift(const EvalData& data, const ShadingFrame& frame, int k) noexcept;

// The source texel index of point (x, y) (any finite coordinates: the tile wraps), and the address
// of its code in `shift` (for a prefetch; null when the bin has no codes).
inline const uint16_t* source_code(const BinShift& shift, uint64_t source) noexcept {
  return shift.codes ? shift.codes + source : nullptr;
}

// The destination texel of point p = (x, y) whose texel has index `source`, in the bin of
// `shift`: floor(p + r_k(source) * factor_k) (Eq. 2 with the bin's depth of the texel containing p
// at the bin's centre direction), r_k = -code * step.
inline void shifted_destination(const BinShift& shift, uint64_t source, double x, double y,
                                int64_t* tx, int64_t* ty) noexcept {
  const double r = shift.codes ? -double(shift.codes[source]) * shift.step : 0.0;
  *tx = int64_t(std::floor(x + r * shift.offset_per_depth[0]));
  *ty = int64_t(std::floor(y + r * shift.offset_per_depth[1]));
}

// The same for one point of view bin k (bin_shift and shifted_destination in one call).
void bin_destination(const EvalData& data, const ShadingFrame& frame, int k, double x, double y,
                     int64_t* tx, int64_t* ty) noexcept;

// What one texel contributes.
struct TexelShading {
  Rgb lobes[model::kLobeCount];  // g(t) per lobe (0 for lobes outside the mask)
  double visibility = 0;         // V(t, i), the stored ASG clamped to [0, 1]
  double gap = 1;                // I(t)
  double sggx_d = 0;             // D_t(h), the fibre SGGX of the texel (specular lobes)
  uint32_t label = 0;            // visibility cluster of t
};

// The integrand's lobes from the BSDF's values at (i, o): f_l |i_z| for the lobes of the frame's
// mask, the delta lobe's weight when i = -o, 0 otherwise.
void integrand_lobes(const ShadingFrame& frame, const model::LobeValues<double>& f,
                     Rgb out[model::kLobeCount]) noexcept;

// V(t, i) of texel index t (< N^2): its stored ASG at the frame's mirrored light, clamped to
// [0, 1], the visibility the integrand uses. No allocation.
double texel_visibility(const EvalData& data, const ShadingFrame& frame, uint64_t t) noexcept;

// g(t) of texel (x, y) (any integers: the tile wraps).
void shade_texel(const EvalData& data, const ShadingFrame& frame, int64_t x, int64_t y,
                 TexelShading* out) noexcept;

}  // namespace clothbake::eval

// The integrand of Eq. 5 at one texel (texel_shading.hpp).
#include "eval/texel_shading.hpp"

#include <cmath>

#include "model/asg.hpp"

namespace clothbake::eval {

bool unit_vector(const double v[3], model::Vec3d* out) noexcept {
  if (v == nullptr || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
    return false;
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(len > 0.0) || !std::isfinite(len)) return false;
  *out = model::Vec3d(v[0] / len, v[1] / len, v[2] / len);
  return true;
}

bool make_frame(const EvalData& data, const double wi[3], const double wo[3], LobeMask mask,
                ShadingFrame* frame, Status* status) noexcept {
  ShadingFrame& f = *frame;
  if (!unit_vector(wi, &f.wi)) {
    *status = Status::error(reader::ErrorCode::InvalidArgument, reader::Check::None,
                            "wi must be a finite non-zero vector");
    return false;
  }
  if (!unit_vector(wo, &f.wo)) {
    *status = Status::error(reader::ErrorCode::InvalidArgument, reader::Check::None,
                            "wo must be a finite non-zero vector");
    return false;
  }
  f.mask = mask;
  f.wi_light = model::Vec3d(f.wi.x, f.wi.y, std::abs(f.wi.z));
  f.h = f.wi + f.wo;
  f.cos_i = std::abs(f.wi.z);
  f.delta = f.wi.x == -f.wo.x && f.wi.y == -f.wo.y && f.wi.z == -f.wo.z;

  // The parallax direction exactly as the reader uses it (mirrored to the upper side, then moved
  // onto the cap's rim below min_cos), and Eq. 2's factor in texel units.
  const double mirrored[3] = {f.wo.x, f.wo.y, std::abs(f.wo.z)};
  double view[3];
  if (!data.parallax.view_direction(mirrored, view).ok()) {
    *status = Status::error(reader::ErrorCode::InvalidArgument, reader::Check::None,
                            "wo cannot be used for the parallax table");
    return false;
  }
  f.view = model::Vec3d(view[0], view[1], view[2]);
  const double n = double(data.n);
  const double on = data.options.parallax ? n : 0.0;  // no parallax: x'(p) = p
  f.offset_per_depth[0] = on * f.view.x / f.view.z;
  f.offset_per_depth[1] = on * f.view.y / f.view.z;
  const model::DirectionGrid<double> parallax_grid{int(data.parallax.dirs()),
                                                   data.parallax.info().min_cos};
  f.parallax_bins = parallax_grid.bilinear_fast(f.view);
  for (int k = 0; k < 4; ++k)
    data.bin_offset_per_depth(uint32_t(f.parallax_bins.index[k]), f.bin_offset_per_depth[k]);
  // A scene-planned asset answers only what its scene can ask (never a number for the rest).
  for (int k = 0; k < 4; ++k)
    if (data.options.parallax && f.parallax_bins.weight[k] > 0.0 &&
        !data.parallax.covers(uint32_t(f.parallax_bins.index[k]))) {
      *status = Status::error(reader::ErrorCode::OutOfPlan, reader::Check::None,
                              "the view direction (%g, %g, %g) needs parallax bin %d, which this "
                              "scene-planned asset left out (bin_map instance 1)",
                              f.wo.x, f.wo.y, f.wo.z, f.parallax_bins.index[k]);
      return false;
    }
  if (data.planned && (data.plan.flags & reader::kPlanNoTransmission) != 0 &&
      f.wi.z * f.wo.z < 0.0) {
    *status = Status::error(reader::ErrorCode::OutOfPlan, reader::Check::None,
                            "light and viewer on opposite sides of the cloth (transmission): this "
                            "scene-planned asset left transmission out (its scene has no light "
                            "behind the cloth)");
    return false;
  }

  // v_c(i) of every cluster, as reader::VisibilityClusterView::mean_visibility sums it.
  const model::DirectionGrid<double> visibility_grid{int(data.clusters.visibility_dirs()), 0.0};
  const model::BinBilinear<double> b = visibility_grid.bilinear(f.wi_light);
  for (uint32_t c = 0; c < data.cluster_count(); ++c) {
    double v = 0.0;
    for (int k = 0; k < 4; ++k)
      v += b.weight[k] * data.clusters.mean_visibility_bin(c, uint32_t(b.index[k]));
    f.mean_visibility[c] = v > 1.0 ? 1.0 : v;  // V <= 1 (clamped); an overshooting lobe mean is not
  }
  return true;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
double texel_depth(const EvalData& data, const ShadingFrame& frame, int64_t x, int64_t y) noexcept {
  return data.parallax.weighted_depth(frame.parallax_bins.index, frame.parallax_bins.weight, x, y);
}
#endif

#ifndef CLOTHBAKE_SINGLE_FILE  // MultiscalePaper's
Rgb texel_diffuse_albedo(const EvalData& data, uint64_t t, model::Lobe lobe) noexcept {
  const YarnShading& yarn = data.yarns[data.maps.yarn_id[t]];
  const float* colour = data.maps.albedo.data + 3 * t;
  return (lobe == model::Lobe::DiffuseReflection ? yarn.diffuse_reflectance
                                                 : yarn.diffuse_transmittance) *
         Rgb(colour[0], colour[1], colour[2]);
}
#endif

ActiveLobes active_lobes(const EvalData& data, const ShadingFrame& frame) noexcept {
  ActiveLobes a;
  const bool reflect = frame.wi.z * frame.wo.z > 0.0, transmit = frame.wi.z * frame.wo.z < 0.0;
  const double h[3] = {frame.h.x, frame.h.y, frame.h.z};
  a.specular_lobe = reflect ? model::Lobe::SpecularReflection : model::Lobe::SpecularTransmission;
  a.diffuse_lobe = reflect ? model::Lobe::DiffuseReflection : model::Lobe::DiffuseTransmission;
  a.specular = (reflect || transmit) && (frame.mask & lobe_bit(a.specular_lobe)) &&
               reader::make_bin_weights(data.specular.tables->bins_per_side(), h, &a.h_bins);
  a.diffuse = (reflect || transmit) && (frame.mask & lobe_bit(a.diffuse_lobe));
  a.sheen = (frame.mask & lobe_bit(model::Lobe::Sheen)) != 0;
  a.delta = frame.delta && (frame.mask & lobe_bit(model::Lobe::DeltaTransmission));
  return a;
}

int draw_view_bin(const ShadingFrame& frame, double u) noexcept {
  double cumulative = 0.0;
  int last = 0;
  for (int k = 0; k < 4; ++k) {
    if (!(frame.parallax_bins.weight[k] > 0.0)) continue;
    cumulative += frame.parallax_bins.weight[k];
    last = k;
    if (u < cumulative) return k;
  }
  return last;
}

BinShift bin_shift(const EvalData& data, const ShadingFrame& frame, int k) noexcept {
  BinShift shift;
  if (!data.options.parallax) return shift;
  const uint32_t bin = uint32_t(frame.parallax_bins.index[k]);
  shift.codes = data.parallax.bin_codes(bin);
  shift.step = data.parallax.depth_step(bin);
  shift.offset_per_depth[0] = frame.bin_offset_per_depth[k][0];
  shift.offset_per_depth[1] = frame.bin_offset_per_depth[k][1];
  return shift;
}

void bin_destination(const EvalData& data, const ShadingFrame& frame, int k, double x, double y,
                     int64_t* tx, int64_t* ty) noexcept {
  const BinShift shift = bin_shift(data, frame, k);
  shifted_destination(shift, data.texel(int64_t(std::floor(x)), int64_t(std::floor(y))), x, y, tx,
                      ty);
}

void integrand_lobes(const ShadingFrame& frame, const model::LobeValues<double>& f,
                     Rgb out[model::kLobeCount]) noexcept {
  for (int l = 0; l < model::kLobeCount; ++l) {
    const model::Lobe lobe = model::Lobe(l);
    if (!(frame.mask & lobe_bit(lobe)))
      out[l] = Rgb();
    else if (lobe == model::Lobe::DeltaTransmission)
      out[l] = frame.delta ? f.delta_transmission : Rgb();
    else
      out[l] = f[lobe] * frame.cos_i;
  }
}

double texel_visibility(const EvalData& data, const ShadingFrame& frame, uint64_t t) noexcept {
  // V exactly as reader::VisibilityAsgView::visibility computes it, for the mirrored direction.
  const model::Asg<double> lobe = model::asg_from_params(data.visibility.lobe_at(t));
  const double v = model::asg_eval(lobe, frame.wi_light);
  return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
}

void shade_texel(const EvalData& data, const ShadingFrame& frame, int64_t x, int64_t y,
                 TexelShading* out) noexcept {
  const uint64_t t = data.texel(x, y);
  const model::ClothBsdf<double> bsdf(data.texel_params(t));
  const double visibility = texel_visibility(data, frame, t);
  integrand_lobes(frame, bsdf.eval(frame.wi, frame.wo, visibility), out->lobes);
  out->visibility = visibility;
  out->gap = bsdf.gap();
  out->sggx_d = bsdf.sggx().D(frame.h);
  out->label = data.clusters.label_at(t);
}

}  // namespace clothbake::eval

// Clustered control variates over a footprint in the paper's form, Eq. 8-10 as printed
// (methods.hpp; docs/evaluator.md, "Multi-scale as printed").
#include <cmath>

#include "eval/footprint_samples.hpp"
#include "eval/methods.hpp"
#include "model/spongecake.hpp"

namespace clothbake::eval {
namespace {

using model::Lobe;

// The per-footprint constants of the control variate g (docs/evaluator.md, "Multi-scale as
// printed"):
//   specular  g(q) = kbar G |i_z| T_sheen v_c(q) T_c(q)(q, h)  (T: the table value, I D binned;
//                    kbar the footprint mean of k)
//   diffuse   g(q) = |i_z| / pi T_sheen v_c(q) I(q) R(q)       (R = R_d or T_d times the colour)
//   sheen     g(q) = colour sheen(i, o) |i_z| v_c(q)
//   delta     g(q) = T_sheen v_c(q) T_gap(q)                   (T_gap = 1 - I, from its table)
struct PaperConstants : ActiveLobes {
  Rgb diffuse_scale, sheen_scale, delta_scale;
  reader::BinWeights gap_bin;
  // kbar_c G-bar |i_z| T_sheen per cluster, RGB (the first 3 C entries are set; a plain array so
  // that the 255-cluster capacity costs no initialisation per estimate).
  double specular_scale[3 * reader::kMaxVisibilityClusters];
  Rgb scale(uint32_t c) const {
    return Rgb(specular_scale[3 * c], specular_scale[3 * c + 1], specular_scale[3 * c + 2]);
  }
};

// g of every active lobe but the specular one at texel q (integer coordinates, any: the tile
// wraps); the specular lobe has its own residual, Eq. 9's.
void control_variate(const EvalData& data, const ShadingFrame& frame, const PaperConstants& k,
                     int64_t qx, int64_t qy, Rgb g[model::kLobeCount]) {
  const uint64_t t = data.texel(qx, qy);
  const uint32_t x = uint32_t(t % data.n), y = uint32_t(t / data.n);
  const uint32_t label = data.clusters.label(x, y);
  const double vbar = frame.mean_visibility[label];
  const double gap = data.maps.gap[t];
  if (k.diffuse)
    g[int(k.diffuse_lobe)] =
        k.diffuse_scale * (texel_diffuse_albedo(data, t, k.diffuse_lobe) * gap) * vbar;
  if (k.sheen) g[int(Lobe::Sheen)] = k.sheen_scale * vbar;
  if (k.delta) {
    if (data.gap.present()) {
      int cluster = -1;
      const double value = data.gap.texel_value(k.gap_bin, x, y, label, &cluster);
      g[int(Lobe::DeltaTransmission)] =
          cluster < 0 ? Rgb() : k.delta_scale * (frame.mean_visibility[cluster] * value);
    } else {
      g[int(Lobe::DeltaTransmission)] = k.delta_scale * ((1.0 - gap) * vbar);
    }
  }
}

// sum over clusters c of v_c(i) values[c] (one channel per cluster).
double visibility_weighted(const ShadingFrame& frame, uint32_t clusters, const double* values) {
  double sum = 0.0;
  for (uint32_t c = 0; c < clusters; ++c)
    sum += frame.mean_visibility[c] * values[c];
  return sum;
}

// sum over clusters c of v_c(i) values[3c .. 3c + 2] (RGB per cluster).
Rgb visibility_weighted_rgb(const ShadingFrame& frame, uint32_t clusters, const double* values) {
  Rgb sum;
  for (uint32_t c = 0; c < clusters; ++c)
    sum += Rgb(values[3 * c], values[3 * c + 1], values[3 * c + 2]) * frame.mean_visibility[c];
  return sum;
}

}  // namespace

Status paper_control_variates(const EvalData& data, const ShadingFrame& frame, const Footprint& p,
                              uint32_t spp, Rng& rng, Estimate* out) noexcept {
  const uint32_t n = data.n, clusters = data.cluster_count();
  const double area = (p.x1 - p.x0) * (p.y1 - p.y0);

  // The parallax transition (Sec. 5.2): one shift of P by its mean offset for o, the exact
  // footprint mean from the parallax SATs.
  double dx = 0.0, dy = 0.0;
  {
    const double view[3] = {frame.view.x, frame.view.y, frame.view.z};
    reader::ParallaxSample mean;
    Status status = data.parallax.footprint_depth(p, view, &mean);
    if (!status.ok()) return status;
    const double shift = data.options.parallax ? double(n) : 0.0;
    dx = mean.offset[0] * shift;
    dy = mean.offset[1] * shift;
  }
  const Footprint shifted{p.x0 + dx, p.y0 + dy, p.x1 + dx, p.y1 + dy};
  reader::FootprintPlan plan;
  if (!reader::make_footprint_plan(shifted, n, &plan))
    return reader::plan_footprint(shifted, n, &plan);
  out->counters.table_queries += 1;

  // PaperConstants from the texel at the centre of the shifted footprint (Eq. 10's p-bar).
  const uint64_t centre_texel = data.texel(int64_t(std::floor(0.5 * (shifted.x0 + shifted.x1))),
                                           int64_t(std::floor(0.5 * (shifted.y0 + shifted.y1))));
  const model::ClothBsdf<double> centre(data.texel_params(centre_texel));
  const Rgb t_sheen = centre.sheen_transmittance(frame.wo);
  const bool reflect = frame.wi.z * frame.wo.z > 0.0;
  const double cos_i = frame.cos_i;
  const double h[3] = {frame.h.x, frame.h.y, frame.h.z};
  PaperConstants k;
  static_cast<ActiveLobes&>(k) = active_lobes(data, frame);

  Rgb base[model::kLobeCount];
  double values[3 * reader::kMaxVisibilityClusters];
  if (k.specular) {
    // Eq. 9-11: kbar G-bar (v-bar F), G-bar the SpongeCake attenuation f / (alpha D) of the centre
    // texel and kbar the footprint mean of k.
    const double d_h = centre.sggx().D(frame.h);
    const double f = reflect ? model::spongecake_reflection(
                                   centre.sggx(), centre.optical_thickness(), frame.wi, frame.wo)
                             : model::spongecake_transmission(
                                   centre.sggx(), centre.optical_thickness(), frame.wi, frame.wo);
    const double g_bar = d_h > 0.0 ? f / d_h : 0.0;
    data.sums.integral(plan, data.sums.layout().albedo(), 3, values);
    const Rgb scale = Rgb(values[0], values[1], values[2]) / area * (t_sheen * (g_bar * cos_i));
    out->counters.table_queries += 1;
    for (uint32_t c = 0; c < clusters; ++c)
      for (int ch = 0; ch < 3; ++ch)
        k.specular_scale[3 * c + ch] = scale[ch];
    if (!data.specular.tables->try_query_all(shifted, h, values))
      return Status::error(reader::ErrorCode::InvalidArgument, reader::Check::None,
                           "specular tables: footprint query failed");
    Rgb sum;
    for (uint32_t c = 0; c < clusters; ++c)
      sum += k.scale(c) * (frame.mean_visibility[c] * values[c]);
    base[int(k.specular_lobe)] = sum / area;
    out->counters.table_queries += 1;
  }
  if (k.diffuse) {
    k.diffuse_scale = t_sheen * (cos_i * model::kInvPi<double>);
    const uint32_t first = k.diffuse_lobe == Lobe::DiffuseReflection
                               ? data.sums.layout().diffuse_r()
                               : data.sums.layout().diffuse_t();
    data.sums.integral(plan, first, 3 * clusters, values);
    base[int(k.diffuse_lobe)] =
        k.diffuse_scale * visibility_weighted_rgb(frame, clusters, values) / area;
    out->counters.table_queries += 1;
  }
  if (k.sheen) {
    k.sheen_scale = centre.eval(frame.wi, frame.wo, 1.0).sheen * cos_i;
    data.sums.integral(plan, data.sums.layout().area(), clusters, values);
    base[int(Lobe::Sheen)] = k.sheen_scale * (visibility_weighted(frame, clusters, values) / area);
    out->counters.table_queries += 1;
  }
  if (k.delta) {
    k.delta_scale = t_sheen;
    if (data.gap.present()) {
      const double any[3] = {0.0, 0.0, 1.0};
      reader::make_bin_weights(1, any, &k.gap_bin);
      if (!data.gap.tables->try_query_all(shifted, any, values))
        return Status::error(reader::ErrorCode::InvalidArgument, reader::Check::None,
                             "gap tables: footprint query failed");
    } else {
      data.sums.integral(plan, data.sums.layout().gap(), clusters, values);
    }
    base[int(Lobe::DeltaTransmission)] =
        k.delta_scale * (visibility_weighted(frame, clusters, values) / area);
    out->counters.table_queries += 1;
  }

  // The residual at spp stratified points p in P, everything at p + mean offset: f - g for the
  // lobes whose g is exact per texel, and Eq. 9's kbar G-bar I D (V - v_c) for the specular lobe.
  Rgb residual[model::kLobeCount];
  TexelShading shading;
  stratified_points(p, spp, rng, [&](double x, double y) {
    const int64_t qx = int64_t(std::floor(x + dx)), qy = int64_t(std::floor(y + dy));
    Rgb g[model::kLobeCount];
    shade_texel(data, frame, qx, qy, &shading);
    control_variate(data, frame, k, qx, qy, g);
    for (int l = 0; l < model::kLobeCount; ++l)
      residual[l] += shading.lobes[l] - g[l];
    if (k.specular) {
      const int s = int(k.specular_lobe);
      const double deviation = shading.visibility - frame.mean_visibility[shading.label];
      residual[s] += k.scale(0) * (shading.gap * shading.sggx_d * deviation) - shading.lobes[s];
    }
  });
  for (int l = 0; l < model::kLobeCount; ++l)
    out->lobes[l] += base[l] + residual[l] / double(spp);
  out->counters.samples += spp;
  out->counters.texel_evals += spp;
  return {};
}

}  // namespace clothbake::eval

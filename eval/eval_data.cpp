// Per-texel parameters and table values of an open evaluator (eval_data.hpp).
#include "eval/eval_data.hpp"

namespace clothbake::eval {

void EvalData::bin_offset_per_depth(uint32_t bin, double out[2]) const {
  out[0] = out[1] = 0.0;
  if (!options.parallax) return;
  const model::DirectionGrid<double> grid{int(parallax.dirs()), parallax.info().min_cos};
  const model::Vec3d c = grid.bin_center(int(bin % uint32_t(grid.n)), int(bin / uint32_t(grid.n)));
  out[0] = double(n) * c.x / c.z;
  out[1] = double(n) * c.y / c.z;
}

model::TexelParams<double> EvalData::texel_params(uint64_t t) const {
  model::TexelParams<double> p;
  const YarnShading& yarn = yarns[maps.yarn_id[t]];
  const float* tangent = maps.tangent.data + 3 * t;
  const float* colour = maps.albedo.data + 3 * t;
  const Rgb c(colour[0], colour[1], colour[2]);
  p.tangent = model::Vec3d(tangent[0], tangent[1], tangent[2]);
  p.roughness = yarn.roughness;
  p.optical_thickness = yarn.optical_thickness;
  p.specular_albedo = yarn.specular_albedo * c;
  p.diffuse_reflectance = yarn.diffuse_reflectance * c;
  p.diffuse_transmittance = yarn.diffuse_transmittance * c;
  p.gap = maps.gap[t];
  p.sheen_color = sheen_color;
  p.sheen_roughness = sheen_roughness;
  p.sheen_convention = options.sheen_convention;
  return p;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // not used by shading
double TableSource::texel_value(const reader::BinWeights& weights, uint32_t x, uint32_t y,
                                uint32_t label, int* cluster) const noexcept {
  if (is_compressed()) return compressed.texel_value(weights, x, y, cluster);
#ifdef CLOTHBAKE_SINGLE_FILE
  (void)weights, (void)x, (void)y, (void)label;
  *cluster = -1;
  return 0.0;  // unreachable: the single file opens compressed tables only
#else
  const int column = raw.column_of_cluster(label);
  *cluster = column < 0 ? -1 : int(label);
  if (column < 0) return 0.0;
  double v = 0.0;
  for (uint32_t k = 0; k < weights.count; ++k)
    v += weights.weight[k] * raw.texel_value(weights.bin[k], x, y, uint32_t(column));
  return v;
#endif
}
#endif

}  // namespace clothbake::eval

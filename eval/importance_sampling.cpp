// BSDF importance sampling of a footprint's representative texel (evaluator.hpp,
// Evaluator::sample_direction).
#include <cmath>

#include "eval/eval_data.hpp"
#include "eval/evaluator.hpp"
#include "eval/texel_shading.hpp"

namespace clothbake::eval {
namespace {

using reader::Check;
using reader::ErrorCode;

// The representative texel of a footprint for view direction o (unit).
Status centre_texel(const EvalData& d, const Footprint& p, const model::Vec3d& o, uint64_t* t) {
  reader::FootprintPlan plan;
  if (!reader::make_footprint_plan(p, d.n, &plan)) return reader::plan_footprint(p, d.n, &plan);
  const double view[3] = {o.x, o.y, std::abs(o.z)};
  reader::ParallaxSample s;
  const bool area = p.x1 > p.x0 && p.y1 > p.y0;
  const Status status =
      area ? d.parallax.footprint_depth(p, view, &s)
           : d.parallax.depth(int64_t(std::floor(p.x0)), int64_t(std::floor(p.y0)), view, &s);
  if (!status.ok()) return status;
  const double n = d.options.parallax ? double(d.n) : 0.0;
  const double cx = area ? 0.5 * (p.x0 + p.x1) : p.x0, cy = area ? 0.5 * (p.y0 + p.y1) : p.y0;
  *t =
      d.texel(int64_t(std::floor(cx + s.offset[0] * n)), int64_t(std::floor(cy + s.offset[1] * n)));
  return {};
}

// The technique probabilities for a footprint whose representative texel has parameters `params`
// and BSDF `bsdf`: its own, and for a footprint with area in a tile with both yarn and gaps a
// mixture with weight kOtherSide of the same texel's made half yarn, half gap (I = 1/2). At t alone
// a footprint centred on a yarn could never draw the delta lobe through the gaps it covers, nor one
// centred on a gap its yarns' continuous lobes: that light would be lost (docs/evaluator.md,
// "Importance sampling").
constexpr double kOtherSide = 0.25;
model::TechniqueProbabilities<double> techniques(const EvalData& d, const Footprint& p,
                                                 const model::TexelParams<double>& params,
                                                 const model::ClothBsdf<double>& bsdf,
                                                 const model::Vec3d& o) {
  model::TechniqueProbabilities<double> pa = bsdf.technique_probabilities(o);
  if (!(p.x1 > p.x0 && p.y1 > p.y0 && d.has_gaps && d.has_yarn)) return pa;
  model::TexelParams<double> half = params;
  half.gap = 0.5;
  const model::TechniqueProbabilities<double> q =
      model::ClothBsdf<double>(half).technique_probabilities(o);
  double sum = 0;
  for (int k = 0; k < model::kTechniqueCount; ++k)
    sum += (pa.p[k] = (1 - kOtherSide) * pa.p[k] + kOtherSide * q.p[k]);
  for (double& v : pa.p)
    v = sum > 0 ? v / sum : 0.0;  // one side without any technique: the other's alone
  return pa;
}

}  // namespace

Status Evaluator::sample_direction(const Footprint& footprint, const double wo[3], double u_lobe,
                                   double u1, double u2, DirectionSample* out) const noexcept {
  if (!data_ || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "evaluator is not open");
  model::Vec3d o;
  if (!unit_vector(wo, &o))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "wo must be a finite non-zero vector");
  uint64_t t = 0;
  const Status s = centre_texel(*data_, footprint, o, &t);
  if (!s.ok()) return s;
  const model::TexelParams<double> params = data_->texel_params(t);
  const model::ClothBsdf<double> bsdf(params);
  const model::BsdfSample<double> b =
      bsdf.sample(techniques(*data_, footprint, params, bsdf, o), o, u_lobe, u1, u2);
  *out = DirectionSample{};
  out->valid = b.valid;
  out->is_delta = b.is_delta;
  out->wi[0] = b.wi.x;
  out->wi[1] = b.wi.y;
  out->wi[2] = b.wi.z;
  out->pdf = b.pdf;
  return {};
}

Status Evaluator::direction_pdf(const Footprint& footprint, const double wi[3], const double wo[3],
                                double* out) const noexcept {
  if (!data_ || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "evaluator is not open");
  model::Vec3d i, o;
  if (!unit_vector(wi, &i) || !unit_vector(wo, &o))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "wi and wo must be finite non-zero vectors");
  uint64_t t = 0;
  const Status s = centre_texel(*data_, footprint, o, &t);
  if (!s.ok()) return s;
  const model::TexelParams<double> params = data_->texel_params(t);
  const model::ClothBsdf<double> bsdf(params);
  *out = bsdf.pdf(techniques(*data_, footprint, params, bsdf, o), i, o);
  return {};
}

}  // namespace clothbake::eval

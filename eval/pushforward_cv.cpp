// The unbiased multi-scale estimate: a clustered control variate at each sample's own destination,
// integrated exactly under the parallax push-forward over the footprint's whole periods or whole
// source blocks, the rest by cheap samples (methods.hpp, footprint_cover.hpp; docs/evaluator.md,
// "Unbiased multi-scale").
#include <algorithm>
#include <cmath>

#include "eval/footprint_samples.hpp"
#include "eval/methods.hpp"
#include "eval/visibility_pilot.hpp"
#include "model/spongecake.hpp"

namespace clothbake::eval {
namespace {

using model::Lobe;

constexpr uint32_t kMaxRank = reader::kMaxVisibilityBasisRank;
constexpr uint32_t kStackImages = 1024;
constexpr uint64_t kMaxVisibilitySamples = uint64_t(1) << 22;  // an estimate's, at any spp

// What g needs per estimate (docs/evaluator.md, "Unbiased multi-scale"):
//   g(t) = sum over the lobes asked for of
//     specular  s_c T(t, h) v(t)            s_c = kbar_c G_y(c) |i_z| T_sheen (RGB), T the table
//     diffuse   |i_z| / pi T_sheen I(t) R(t) v(t)
//     sheen     colour sheen(i, o) |i_z| v(t)
//     delta     T_sheen (1 - I(t)) v(t)     (when i = -o)
//   v(t) = sum_j b_cj(i) e_j(t), c = cluster of t, b_cj the visibility basis at the light.
struct PushforwardConstants : ActiveLobes {
  Rgb diffuse_scale, sheen_scale, delta_scale;
  uint32_t rank = 0;
  // Per cluster: b_cj(i), j = 0..M (plain arrays: the 255-cluster capacity costs nothing).
  double vis[reader::kMaxVisibilityClusters][kMaxRank + 1];
  Rgb specular_scale[reader::kMaxVisibilityClusters];     // s_c
  Rgb attenuation_scale[reader::kMaxVisibilityClusters];  // s_c without kbar_c (g_V's)
  // Per compressed image i: sum_b w_b(h) basis_i(b), the image's value at h (the table value of a
  // texel is the sum of its image weights times these).
  const double* image_at_h = nullptr;
  // g_V's: the light direction of the visibility look-ups and h (ShadingFrame's).
  model::Vec3d light, h;
  // g_V with each texel's own attenuation (EvalData::texel_attenuation): wi, wo and
  // T_sheen |i_z|, the factor of f's specular lobe besides the texel's albedo, gap, V and f_s.
  bool own_attenuation = false;
  model::Vec3d wi, wo, h_unit;
  double iz = 0.0, oz = 0.0, inv_cosines = 0.0;  // |i_z|, |o_z|, 1 / (|i_z| |o_z|)
  Rgb own_scale;
};

// f_s per unit albedo in reflection (Eq. 10 at the texel's tangent: spongecake_reflection's value
// for unit wi, wo), with |i_z|, |o_z| and the unit half vector from k and, for unit t and w,
// sigma(w) = sqrt(1 - (1 - sigma^2) (t.w)^2) and D(h) = d_norm / q^2.
inline double own_specular(const PushforwardConstants& k, const YarnShading& yarn,
                           const model::FibreSggx<double>& sggx) {
  const double ci = dot(sggx.t, k.wi), co = dot(sggx.t, k.wo), ch = dot(sggx.t, k.h_unit);
  const double si = std::sqrt(1.0 - sggx.one_minus_sigma2 * ci * ci);
  const double so = std::sqrt(1.0 - sggx.one_minus_sigma2 * co * co);
  const double q = sggx.sigma2 + sggx.one_minus_sigma2 * (ch * ch), denom = si * k.oz + so * k.iz;
  // 1 - e^-tau (0 without a slab, as spongecake_reflection reads a thickness <= 0 or NaN): g_V need
  // not match f to the last bit (any g_V keeps the estimate unbiased), and exp in place of expm1
  // took the 182 samples' added cost from 3.1-3.3 to 1.8-1.9 us (docs/performance.md).
  const double thickness = yarn.optical_thickness > 0.0 ? yarn.optical_thickness : 0.0;
  const double tau = thickness * denom * k.inv_cosines;
  return sggx.d_norm * (tau < 1e-4 ? tau : 1.0 - std::exp(-tau)) / (4.0 * q * q * denom);
}

// g_V at texel index t (< N^2), added to exact[]: g with the texel's own visibility V(t, i), its
// own I(t) D_t(h) in place of the table value and its own specular albedo, from its one-line
// record (cv_texels.hpp's Exact).
void exact_variate(const EvalData& data, const PushforwardConstants& k, uint64_t t,
                   Rgb exact[model::kLobeCount]) {
  const ControlVariateTexels::Exact& x = data.cv_texels.exact(t);
  const double visibility = x.visibility(k.light);
  const YarnShading& yarn = data.yarns[x.yarn];
  const double gap = x.gap;
  const Rgb colour(x.colour[0], x.colour[1], x.colour[2]);
  if (k.specular) {
    model::FibreSggx<double> sggx = yarn.sggx;  // the yarn's roughness, the texel's tangent
    sggx.t = model::Vec3d(x.tangent[0], x.tangent[1], x.tangent[2]);
    const double specular = k.own_attenuation ? own_specular(k, yarn, sggx) : sggx.D(k.h);
    exact[int(k.specular_lobe)] +=
        (k.own_attenuation ? k.own_scale : k.attenuation_scale[x.cluster]) * yarn.specular_albedo *
        colour * (gap * specular * visibility);
  }
  if (k.diffuse) {
    const Rgb albedo = (k.diffuse_lobe == Lobe::DiffuseReflection ? yarn.diffuse_reflectance
                                                                  : yarn.diffuse_transmittance) *
                       colour;
    exact[int(k.diffuse_lobe)] += k.diffuse_scale * albedo * (gap * visibility);
  }
  if (k.sheen) exact[int(Lobe::Sheen)] += k.sheen_scale * visibility;
  if (k.delta) exact[int(Lobe::DeltaTransmission)] += k.delta_scale * ((1.0 - gap) * visibility);
}

// g of every lobe asked for at texel index t (< N^2), added to g[]; when `low` is not null g_r, the
// same with the visibility basis cut at rank `low_rank`, added to low[]: one packed record
// (cv_texels.hpp) and the per-estimate constants.
void control_variate(const EvalData& data, const PushforwardConstants& k, uint64_t t,
                     Rgb g[model::kLobeCount], uint32_t low_rank = 0, Rgb* low = nullptr) {
  const ControlVariateTexels& records = data.cv_texels;
  const ControlVariateTexels::Header& texel = records.header(t);
  const double* b = k.vis[texel.label];
  double v = b[0], v_low = b[0];
  const float* e = records.coefficients(t);
  for (uint32_t j = 0; j < k.rank; ++j) {
    v += b[j + 1] * double(e[j]);
    if (j + 1 == low_rank) v_low = v;
  }
  // Each lobe's factor and scalar without the visibility, then times v (and v_low).
  auto add = [&](model::Lobe lobe, const Rgb& factor, double scalar) {
    g[int(lobe)] += factor * (scalar * v);
    if (low) low[int(lobe)] += factor * (scalar * v_low);
  };
  const double gap = texel.gap;
  const Rgb colour(texel.colour[0], texel.colour[1], texel.colour[2]);
  if (k.specular && texel.count > 0) {
    // The table value at h: image `first` (the cell mean) has weight 1, the others their stored
    // coefficients.
    const double* at_h = k.image_at_h + texel.first_image;
    const int16_t* q = records.image_weights(t);
    double value = at_h[0];
    for (uint32_t j = 1; j < texel.count; ++j)
      value += double(q[j - 1]) * at_h[j];
    add(k.specular_lobe, k.specular_scale[data.image_cluster[texel.first_image]], value);
  }
  if (k.diffuse) {
    const YarnShading& yarn = data.yarns[texel.yarn];
    const Rgb albedo = (k.diffuse_lobe == Lobe::DiffuseReflection ? yarn.diffuse_reflectance
                                                                  : yarn.diffuse_transmittance) *
                       colour;
    add(k.diffuse_lobe, k.diffuse_scale * albedo, gap);
  }
  if (k.sheen) add(Lobe::Sheen, k.sheen_scale, 1.0);
  if (k.delta) add(Lobe::DeltaTransmission, k.delta_scale, 1.0 - gap);
}

inline void prefetch(const void* address) noexcept {
#if defined(__GNUC__) || defined(__clang__)
  if (address != nullptr) __builtin_prefetch(address);
#else
  (void)address;
#endif
}

// Every cache line of texel t's record (cv_texels.hpp).
inline void prefetch_record(const EvalData& data, uint64_t t) noexcept {
  const char* record = static_cast<const char*>(data.cv_texels.address(t));
  const uint32_t stride = data.cv_texels.stride();
  for (uint32_t offset = 0; offset < stride; offset += 64)
    prefetch(record + offset);
  prefetch(record + stride - 1);
}

// What a sample point's evaluation reads, to prefetch (PointBatch::resolve).
enum Reads : unsigned { kRecord = 1, kExact = 2, kMaps = 4 };

// Up to kCapacity sample points of one view bin in two stages, so that their cache misses overlap:
// add() keeps a point and prefetches its source texel's parallax code; resolve() computes every
// kept point's destination texel and prefetches what it reads. The caller evaluates afterwards.
template <uint32_t kCapacity>
struct PointBatch {
  struct Point {
    double x, y;
    uint64_t source;
  };
  uint32_t count = 0;
  Point points[kCapacity];
  uint64_t destination[kCapacity];

  void add(const EvalData& data, const BinShift& shift, double x, double y) noexcept {
    const uint64_t source = data.texel(int64_t(std::floor(x)), int64_t(std::floor(y)));
    prefetch(source_code(shift, source));
    points[count++] = {x, y, source};
  }
  // What of each destination to prefetch (Reads): its record of g, its record of g_V, the maps
  // shade_texel reads besides (the tangent and the visibility lobe); `first_reads` for the first
  // `first` points (an early batch's residual points), `reads` for the rest.
  void resolve(const EvalData& data, const BinShift& shift, unsigned reads,
               unsigned first_reads = 0, uint32_t first = 0) noexcept {
    for (uint32_t i = 0; i < count; ++i) {
      const unsigned what = i < first ? first_reads : reads;
      int64_t tx = 0, ty = 0;
      shifted_destination(shift, points[i].source, points[i].x, points[i].y, &tx, &ty);
      destination[i] = data.texel(tx, ty);
      if (what & kRecord) prefetch_record(data, destination[i]);
      if (what & kExact) prefetch(&data.cv_texels.exact(destination[i]));
      if (what & kMaps) {
        prefetch(data.maps.tangent.data + 3 * destination[i]);
        prefetch(data.visibility.record_address(destination[i]));
      }
    }
  }
};

// Every cache line of [begin, begin + bytes).
inline void prefetch_lines(const void* begin, std::size_t bytes) noexcept {
  const char* p = static_cast<const char*>(begin);
  for (std::size_t offset = 0; offset < bytes; offset += 64)
    prefetch(p + offset);
}

// Calls visit(t, x, y) with the destination texel index t (< N^2) of each of `count` stratified
// points (x, y) of `rect` (stratified_points' order and draws) in the bin of `shift`. The points go
// in chunks: their source texels' codes are prefetched as they are drawn, then the destinations'
// records, then visit runs, so that a chunk's cache misses overlap instead of queueing one sample
// at a time (the samples land at random texels of planes and records of megabytes).
template <class Visit>
void visit_destinations(const EvalData& data, const BinShift& shift, const Footprint& rect,
                        uint32_t count, Rng& rng, Visit visit, unsigned reads) {
  PointBatch<16> chunk;
  auto flush = [&] {
    chunk.resolve(data, shift, reads);
    for (uint32_t i = 0; i < chunk.count; ++i)
      visit(chunk.destination[i], chunk.points[i].x, chunk.points[i].y);
    chunk.count = 0;
  };
  stratified_points(rect, count, rng, [&](double x, double y) {
    chunk.add(data, shift, x, y);
    if (chunk.count == 16) flush();
  });
  flush();
}

// The two loops of the base that run over every compressed image are compiled twice on x86-64
// Linux with GCC: for the baseline and for x86-64-v3 (AVX2), picked once when the program loads.
// Both add the same products in the same order (no contraction into FMA under ISO C++), so the
// estimate does not depend on the machine's choice.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define CLOTHBAKE_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define CLOTHBAKE_VECTOR_CLONES
#endif

// Each image's value at h: out[i] = sum_q weights[q] rows[q][i], i < images (the four bins' rows
// of the tables' basis; unused bins have weight 0).
CLOTHBAKE_VECTOR_CLONES void images_at_h(const float* const rows[4], const double weights[4],
                                         uint32_t images, double* out) noexcept {
  for (uint32_t i = 0; i < images; ++i)
    out[i] = weights[0] * double(rows[0][i]) + weights[1] * double(rows[1][i]) +
             weights[2] * double(rows[2][i]) + weights[3] * double(rows[3][i]);
}

// Per cluster c (< clusters): sum_j vis[c][j] sum_{images i of c} image_at_h[i] s[i r1 + j], into
// out[c], where s = sum_q weight[q] sums[q] over `points` vectors of sums (the whole-tile sums, or
// the signed prefix points of a block rectangle), combined as they are read. A cluster's images are
// one range (begin[c] .. begin[c + 1]); they are summed in two interleaved partial sums per
// component (no chain of dependent additions through the images). kR: r1 known at compile time
// (0: read `r1`).
template <uint32_t kR, typename S>
CLOTHBAKE_VECTOR_CLONES void cluster_specular_sums(const uint32_t* begin, uint32_t clusters,
                                                   const double* image_at_h, const S* const* sums,
                                                   const double* weight, uint32_t points,
                                                   uint32_t r1_runtime,
                                                   const double (*vis)[kMaxRank + 1],
                                                   double* out) noexcept {
  const uint32_t r1 = kR ? kR : r1_runtime;
  for (uint32_t c = 0; c < clusters; ++c) {
    double even[kMaxRank + 1] = {}, odd[kMaxRank + 1] = {};
    uint32_t i = begin[c];
    const uint32_t end = begin[c + 1];
    for (; i + 1 < end; i += 2) {
      const double b0 = image_at_h[i], b1 = image_at_h[i + 1];
      for (uint32_t q = 0; q < points; ++q) {
        const S* s0 = sums[q] + uint64_t(i) * r1;
        const S* s1 = s0 + r1;
        const double w0 = b0 * weight[q], w1 = b1 * weight[q];
        for (uint32_t j = 0; j < r1; ++j) {
          even[j] += w0 * s0[j];
          odd[j] += w1 * s1[j];
        }
      }
    }
    if (i < end) {
      for (uint32_t q = 0; q < points; ++q) {
        const S* s0 = sums[q] + uint64_t(i) * r1;
        const double w0 = image_at_h[i] * weight[q];
        for (uint32_t j = 0; j < r1; ++j)
          even[j] += w0 * s0[j];
      }
    }
    double v = 0.0;
    for (uint32_t j = 0; j < r1; ++j)
      v += vis[c][j] * (even[j] + odd[j]);
    out[c] = v;
  }
}

// Eq. 10's attenuation f_s / D for the fibre `params` with its tangent turned normal to h: the
// fibres of a yarn that mirror i into o have t . h = 0, and their projected areas, not those of
// the yarn's mean fibre, set the attenuation of the light they reflect (docs/evaluator.md).
double attenuation(model::TexelParams<double> params, const ShadingFrame& frame, bool reflect) {
  const double hh = dot(frame.h, frame.h);
  if (hh > 0.0) {
    const model::Vec3d t = params.tangent - frame.h * (dot(params.tangent, frame.h) / hh);
    if (dot(t, t) > 1e-12 * dot(params.tangent, params.tangent)) params.tangent = t;
  }
  const auto sggx = model::FibreSggx<double>::make(params.tangent, params.roughness);
  const double d = sggx.D(frame.h);
  if (!(d > 0.0)) return 0.0;
  const double thickness = params.optical_thickness > 0.0 ? params.optical_thickness : 0.0;
  const double f = reflect ? model::spongecake_reflection(sggx, thickness, frame.wi, frame.wo)
                           : model::spongecake_transmission(sggx, thickness, frame.wi, frame.wo);
  return f / d;
}

// The per-lobe integral of the control variate at rank layout.rank that the combination
// sum_q weight[q] sums[q] of `points` vectors of push-forward sums (layout's channels) holds,
// added to base[].
template <typename S>
void add_base(const EvalData& data, const PushforwardConstants& k,
              const PushforwardChannels& layout, const S* const* sums, const double* weight,
              uint32_t points, Rgb base[model::kLobeCount]) {
  const uint32_t clusters = data.cluster_count();
  const uint32_t r1 = layout.rank + 1;
  if (k.specular) {
    double per_cluster[reader::kMaxVisibilityClusters];
    const uint32_t* begin = data.cluster_image_begin.data();
    if (r1 == 5)  // the default rank 4: the component loops unrolled
      cluster_specular_sums<5>(begin, clusters, k.image_at_h, sums, weight, points, r1, k.vis,
                               per_cluster);
    else
      cluster_specular_sums<0>(begin, clusters, k.image_at_h, sums, weight, points, r1, k.vis,
                               per_cluster);
    Rgb sum;
    for (uint32_t c = 0; c < clusters; ++c)
      sum += k.specular_scale[c] * per_cluster[c];
    base[int(k.specular_lobe)] += sum;
  }
  const uint32_t diffuse_offset = k.diffuse_lobe == Lobe::DiffuseReflection ? 0 : 3;
  Rgb diffuse;
  double sheen = 0.0, delta = 0.0;
  for (uint32_t c = 0; c < clusters; ++c)
    for (uint32_t j = 0; j < r1; ++j) {
      const double b = k.vis[c][j];
      double d[3] = {0.0, 0.0, 0.0}, sh = 0.0, de = 0.0;
      for (uint32_t q = 0; q < points; ++q) {
        const S* s = sums[q] + layout.lobe(c, j);
        const double w = weight[q];
        if (k.diffuse)
          for (int ch = 0; ch < 3; ++ch)
            d[ch] += w * double(s[diffuse_offset + ch]);
        sh += w * double(s[6]);
        de += w * double(s[7]);
      }
      if (k.diffuse) diffuse += Rgb(d[0], d[1], d[2]) * b;
      sheen += sh * b;
      delta += de * b;
    }
  if (k.diffuse) base[int(k.diffuse_lobe)] += k.diffuse_scale * diffuse;
  if (k.sheen) base[int(Lobe::Sheen)] += k.sheen_scale * sheen;
  if (k.delta) base[int(Lobe::DeltaTransmission)] += k.delta_scale * delta;
}

// out[ch] = sum_q weight[q] points[q][ch], ch < count.
CLOTHBAKE_VECTOR_CLONES void combine_points(const float* const* points, const double* weight,
                                            uint32_t count_points, uint32_t count,
                                            double* out) noexcept {
  for (uint32_t ch = 0; ch < count; ++ch)
    out[ch] = 0.0;
  for (uint32_t q = 0; q < count_points; ++q) {
    const float* p = points[q];
    const double w = weight[q];
    for (uint32_t ch = 0; ch < count; ++ch)
      out[ch] += w * double(p[ch]);
  }
}

// The prefix points of a block-aligned rectangle (block units) and their weights: the integral
// over it is sum_i weight[i] prefix(point[i]) (reader::FootprintPlan in block units, whose
// corners are grid points). Returns the number of points (at most 9).
struct BlockPoints {
  uint32_t count = 0;
  uint32_t i[9], j[9];
  double weight[9];
};
BlockPoints block_points(const Footprint& units, uint32_t blocks) {
  BlockPoints out;
  reader::FootprintPlan plan;
  if (!reader::make_footprint_plan(units, blocks, &plan)) return out;
  // Points on the grid's first row or column are 0 (exclusive prefix sums); a point named twice
  // gets the sum of its weights.
  auto add = [&](double x, double y, double w) {
    const uint32_t i = uint32_t(x), j = uint32_t(y);
    if (w == 0.0 || i == 0 || j == 0) return;
    for (uint32_t q = 0; q < out.count; ++q)
      if (out.i[q] == i && out.j[q] == j) {
        out.weight[q] += w;
        return;
      }
    out.i[out.count] = i;
    out.j[out.count] = j;
    out.weight[out.count++] = w;
  };
  const double nb = double(blocks);
  // F = [I(rx1, ry1) - I(x0, ry1) - I(rx1, y0) + I(x0, y0)] + qx [I(N, ry1) - I(N, y0)]
  //   + qy [I(rx1, N) - I(x0, N)] + qx qy I(N, N)
  add(plan.rx1, plan.ry1, 1.0);
  add(plan.x0, plan.ry1, -1.0);
  add(plan.rx1, plan.y0, -1.0);
  add(plan.x0, plan.y0, 1.0);
  add(nb, plan.ry1, plan.qx);
  add(nb, plan.y0, -plan.qx);
  add(plan.rx1, nb, plan.qy);
  add(plan.x0, nb, -plan.qy);
  add(nb, nb, plan.qx * plan.qy);
  uint32_t kept = 0;  // weights that cancelled
  for (uint32_t q = 0; q < out.count; ++q)
    if (out.weight[q] != 0.0) {
      out.i[kept] = out.i[q];
      out.j[kept] = out.j[q];
      out.weight[kept++] = out.weight[q];
    }
  out.count = kept;
  return out;
}

}  // namespace

Status pushforward_control_variates(const EvalData& data, const ShadingFrame& frame,
                                    const Footprint& p, const FootprintCover& cover, uint32_t spp,
                                    Rng& rng, Estimate* out, ResidualMoments* moments) noexcept {
  const uint32_t clusters = data.cluster_count();
  const double area = (p.x1 - p.x0) * (p.y1 - p.y0);
  // One view bin for the estimate.
  const int bin = draw_view_bin(frame, rng.uniform());
  // The view's four bins are built together, whichever is drawn: a view's first estimate (a
  // renderer's first frame, a report's warm-up pass) then prepares everything that view will read,
  // and later estimates never pay a build (docs/evaluator.md).
  const bool whole_periods = cover.base == FootprintCover::Base::WholePeriods;
  const bool with_blocks = cover.base == FootprintCover::Base::Blocks;
  // Without a base nothing integrates g exactly, so the control variate is g_V itself (no tables).
  const bool without_base = cover.base == FootprintCover::Base::None;
  const bool needs_g = !without_base || moments != nullptr;  // the pilot's moments read g
  for (int other = 0; other < 4; ++other)
    if (other != bin && frame.parallax_bins.weight[other] > 0.0) {
      const uint32_t index = uint32_t(frame.parallax_bins.index[other]);
      if (whole_periods) (void)data.pushforward.bin_sums(index);
      if (with_blocks) (void)data.subperiod.bin_prefix(index);
    }
  const uint32_t bin_index = uint32_t(frame.parallax_bins.index[bin]);
  // The tables of the base: the whole-tile sums of the whole-period form (any N-long window
  // covers every texel column once, so A's push-forward is kx ky times the tile's), or the block
  // prefix sums of the block form; none without a base.
  const double* sums = whole_periods ? data.pushforward.bin_sums(bin_index) : nullptr;
  const float* prefix = with_blocks ? data.subperiod.bin_prefix(bin_index) : nullptr;
  if ((whole_periods && sums == nullptr) || (with_blocks && prefix == nullptr))
    return Status::error(reader::ErrorCode::Unsupported, reader::Check::None,
                         "cannot allocate the push-forward sums of a view bin");
  const PushforwardChannels& layout =
      with_blocks ? data.subperiod.layout() : data.pushforward.layout();
  const BinShift shift = bin_shift(data, frame, bin);

  // Each image's value at h, once per estimate (on the stack up to kStackImages images, which every
  // example fabric stays under; beyond, one allocation per estimate, made before any point is
  // drawn so that a refusal leaves the generator as the other refusals do).
  double stack_images[kStackImages];
  model::Buffer<double> heap_images;
  double* image_at_h = stack_images;
  if (needs_g && layout.images > kStackImages) {
    if (!heap_images.allocate(layout.images, data.allocator))
      return Status::error(reader::ErrorCode::Unsupported, reader::Check::None,
                           "cannot allocate the images' values at h");
    image_at_h = heap_images.data();
  }

  // The cheap samples of g over the cover's regions.
  const uint32_t m = remainder_samples(data, cover, spp);
  uint32_t counts[5];
  split_remainder_samples(cover, m, counts);
  // An estimate with few samples (2 spp and a remainder of a few dozen) draws all its points now,
  // in the generator's order (the residual's, then each region's), and asks for their parallax
  // codes: they arrive while the constants and the base are computed.
  constexpr uint32_t kEarlyPoints = 64;
  PointBatch<kEarlyPoints> early;
  uint64_t points = spp;
  for (uint32_t r = 0; r < cover.region_count; ++r)
    points += counts[r];
  const bool drawn_early = points <= kEarlyPoints;
  if (drawn_early) {
    auto draw = [&](double x, double y) { early.add(data, shift, x, y); };
    stratified_points(p, spp, rng, draw);
    for (uint32_t r = 0; r < cover.region_count; ++r)
      if (counts[r] > 0) stratified_points(cover.regions[r].rect, counts[r], rng, draw);
  }

  PushforwardConstants k;
  static_cast<ActiveLobes&>(k) = active_lobes(data, frame);
  // The base reads the bin's sums (the block form: its prefix points) and four rows of the tables'
  // basis, kilobytes each at addresses that change with the view and h: asked for now, they
  // arrive while the constants are computed.
  const uint32_t blocks = data.subperiod.blocks();
  const BlockPoints corners = with_blocks ? block_points(cover.blocks, blocks) : BlockPoints{};
  if (whole_periods) prefetch_lines(sums, sizeof(double) * layout.count());
  if (k.specular && needs_g)
    for (uint32_t q = 0; q < k.h_bins.count; ++q)
      prefetch_lines(data.specular.compressed.image_basis_row(k.h_bins.bin[q]),
                     sizeof(float) * layout.images);
  const bool reflect = frame.wi.z * frame.wo.z > 0.0;
  k.rank = data.visibility_rank();
  k.light = frame.wi_light;
  k.h = frame.h;

  // The visibility basis at the light (the stored cluster means when the asset has no basis).
  if (!needs_g) {
    // g_V reads no basis.
  } else if (data.basis.is_open()) {
    const model::DirectionGrid<double> grid{int(data.basis.dirs()), 0.0};
    const model::BinBilinear<double> b = grid.bilinear(frame.wi_light);
    for (uint32_t c = 0; c < clusters; ++c)
      for (uint32_t j = 0; j <= k.rank; ++j) {
        double v = 0.0;
        for (int q = 0; q < 4; ++q)
          v += b.weight[q] * double(data.basis.component(c, j, uint32_t(b.index[q])));
        k.vis[c][j] = v;
      }
  } else {
    for (uint32_t c = 0; c < clusters; ++c)
      k.vis[c][0] = frame.mean_visibility[c];
  }
  const model::ClothBsdf<double> any_texel(data.texel_params(0));
  const Rgb t_sheen = any_texel.sheen_transmittance(frame.wo);  // the fabric's, every texel's
  const double cos_i = frame.cos_i;
  if (k.specular) {
    double yarn_attenuation[64];
    const std::size_t yarns = std::min<std::size_t>(data.yarn_fibre.size(), 64);
    for (std::size_t y = 0; y < yarns; ++y)
      yarn_attenuation[y] = -1.0;  // not evaluated yet: only the yarns of the clusters are
    for (uint32_t c = 0; c < clusters; ++c) {
      const uint32_t y = data.cluster_yarn[c];
      double g = 0.0;
      if (y < yarns) {
        if (yarn_attenuation[y] < 0.0)
          yarn_attenuation[y] = attenuation(data.yarn_fibre[y], frame, reflect);
        g = yarn_attenuation[y];
      } else {
        g = attenuation(data.yarn_fibre[y], frame, reflect);
      }
      k.specular_scale[c] = data.cluster_albedo[c] * t_sheen * (g * cos_i);
      k.attenuation_scale[c] = t_sheen * (g * cos_i);
    }
  }
  // (In reflection |i_z|, |o_z| and h_z are positive.)
  k.own_attenuation = k.specular && reflect &&
                      data.texel_attenuation(std::min(std::abs(frame.wi.z), std::abs(frame.wo.z)));
  k.wi = frame.wi;
  k.wo = frame.wo;
  k.iz = std::abs(frame.wi.z);
  k.oz = std::abs(frame.wo.z);
  k.inv_cosines = 1.0 / (k.iz * k.oz);
  k.h_unit = frame.h / length(frame.h);
  k.own_scale = t_sheen * cos_i;
  if (k.diffuse) k.diffuse_scale = t_sheen * (cos_i * model::kInvPi<double>);
  if (k.sheen) k.sheen_scale = any_texel.eval(frame.wi, frame.wo, 1.0).sheen * cos_i;
  if (k.delta) k.delta_scale = t_sheen;

  // The records asked for before the base is computed (the residual's points: what shade_texel,
  // g and g_V read).
  early.resolve(data, shift, without_base ? kExact : kRecord,
                without_base ? kExact | kMaps : kRecord | kExact | kMaps, spp);

  if (k.specular && needs_g) {
    const reader::CompressedRadianceTables& tables = data.specular.compressed;
    // The four bins' rows at once (a bilinear lookup with fewer bins pads with weight 0).
    const float* rows[4];
    double weights[4];
    for (uint32_t q = 0; q < 4; ++q) {
      const bool used = q < k.h_bins.count;
      rows[q] = tables.image_basis_row(k.h_bins.bin[used ? q : 0]);
      weights[q] = used ? k.h_bins.weight[q] : 0.0;
    }
    images_at_h(rows, weights, layout.images, image_at_h);
  }
  k.image_at_h = image_at_h;

  // The base over A: the per-estimate coefficients dotted with the bin's whole-tile sums (kx ky
  // tiles) or with the block prefix points of A.
  Rgb base[model::kLobeCount];
  if (whole_periods) {
    const double one = 1.0;
    add_base(data, k, layout, &sums, &one, 1, base);
    for (Rgb& b : base)
      b = b * (cover.periods.kx * cover.periods.ky);
  }
  if (with_blocks) {
    const float* points[9];
    for (uint32_t c = 0; c < corners.count; ++c)
      points[c] = prefix + (uint64_t(corners.j[c]) * (blocks + 1) + corners.i[c]) * layout.count();
    // The signed points combined first, channel by channel in double (a loop the compiler
    // vectorises), then one dot product; beyond kCombined channels, combined as they are read.
    constexpr uint32_t kCombined = 4096;
    if (layout.count() <= kCombined) {
      double combined[kCombined];
      combine_points(points, corners.weight, corners.count, layout.count(), combined);
      const double* one_vector = combined;
      const double one = 1.0;
      add_base(data, k, layout, &one_vector, &one, 1, base);
    } else {
      add_base(data, k, layout, points, corners.weight, corners.count, base);
    }
  }
  if (whole_periods || with_blocks) out->counters.table_queries += 1;

  // The residual f - g at spp stratified points over P, both at the sample's destination.
  Rgb residual[model::kLobeCount];
  TexelShading shading;
  const int64_t n = int64_t(data.n);
  // The residual is f - g_V without a base, and with the visibility correction (which integrates
  // g_V - g below); f - g otherwise.
  const bool correct_visibility = !without_base && data.corrects_visibility(frame.cos_i);
  auto residual_sample = [&](uint64_t t, double, double) {
    shade_texel(data, frame, int64_t(t) % n, int64_t(t) / n, &shading);
    Rgb g[model::kLobeCount], g_exact[model::kLobeCount];
    if (!without_base) control_variate(data, k, t, g);
    if (without_base || correct_visibility || moments != nullptr)
      exact_variate(data, k, t, g_exact);
    const Rgb* against = without_base || correct_visibility ? g_exact : g;
    for (int l = 0; l < model::kLobeCount; ++l)
      residual[l] += shading.lobes[l] - against[l];
    if (moments != nullptr) {  // the pilot's: f, g as the forms with a base use it, and g_V
      if (without_base) control_variate(data, k, t, g);
      moments->add(shading.lobes, g, g_exact);
    }
  };
  if (drawn_early)
    for (uint32_t i = 0; i < spp; ++i)
      residual_sample(early.destination[i], 0.0, 0.0);
  else
    visit_destinations(data, shift, p, spp, rng, residual_sample,
                       without_base ? kExact | kMaps : kRecord | kExact | kMaps);
  // The rest of the integral of g by cheap samples, stratified over each region, each region's
  // mean times its area (footprint_cover.hpp): sign g over the whole-period form's rectangles (and
  // g_V over P without a base), g - g_r over the block form's interior, 1_P g - 1_A g_r over its
  // strips.
  const uint32_t low_rank = with_blocks ? layout.rank : k.rank;
  const double side = with_blocks ? double(data.n / blocks) : 0.0;
  const Footprint a{cover.blocks.x0 * side, cover.blocks.y0 * side, cover.blocks.x1 * side,
                    cover.blocks.y1 * side};
  auto inside = [](const Footprint& r, double x, double y) {
    return x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
  };
  Rgb remainder[model::kLobeCount];
  uint32_t next = spp;  // the early points of the regions follow the residual's
  for (uint32_t r = 0; r < cover.region_count; ++r) {
    if (counts[r] == 0) continue;
    const CheapRegion& region = cover.regions[r];
    Rgb piece[model::kLobeCount];
    auto cheap_sample = [&](uint64_t t, double x, double y) {
      if (region.kind == CheapRegion::Kind::Signed) {
        if (without_base)
          exact_variate(data, k, t, piece);
        else
          control_variate(data, k, t, piece);
        return;
      }
      const bool in_p = region.kind == CheapRegion::Kind::Difference || inside(p, x, y);
      const bool in_a = region.kind == CheapRegion::Kind::Difference || inside(a, x, y);
      if (low_rank >= k.rank) {  // g_r is g: 1_P g - 1_A g, one evaluation or none
        if (in_p == in_a) return;
        Rgb g[model::kLobeCount];
        control_variate(data, k, t, g);
        for (int l = 0; l < model::kLobeCount; ++l)
          piece[l] += in_p ? g[l] : g[l] * -1.0;
        return;
      }
      Rgb g[model::kLobeCount], g_low[model::kLobeCount];
      control_variate(data, k, t, g, low_rank, g_low);
      for (int l = 0; l < model::kLobeCount; ++l) {
        if (in_p) piece[l] += g[l];
        if (in_a) piece[l] += g_low[l] * -1.0;
      }
    };
    if (drawn_early)
      for (uint32_t i = 0; i < counts[r]; ++i, ++next)
        cheap_sample(early.destination[next], early.points[next].x, early.points[next].y);
    else
      visit_destinations(data, shift, region.rect, counts[r], rng, cheap_sample,
                         without_base ? kExact : kRecord);
    const double scale = (region.kind == CheapRegion::Kind::Signed ? region.sign : 1.0) *
                         region.area / double(counts[r]);
    for (int l = 0; l < model::kLobeCount; ++l)
      remainder[l] += piece[l] * scale;
  }
  // The visibility correction: the mean of g_V - g over its own stratified points of P (no BSDF
  // evaluation: the texel's ASG and its packed record).
  Rgb correction[model::kLobeCount];
  uint32_t corrections = 0;
  if (correct_visibility) {
    // Where g_V takes the texel's own attenuation, f - g_V vanishes and the correction carries all
    // of f - g: twice the samples there (docs/evaluator.md, step 6).
    const uint64_t kappa = uint64_t(data.options.visibility_samples) * (k.own_attenuation ? 2 : 1);
    corrections = uint32_t(std::min<uint64_t>(kappa * spp, kMaxVisibilitySamples));
    visit_destinations(
        data, shift, p, corrections, rng,
        [&](uint64_t t, double, double) {
          Rgb g[model::kLobeCount], g_exact[model::kLobeCount];
          control_variate(data, k, t, g);
          exact_variate(data, k, t, g_exact);
          for (int l = 0; l < model::kLobeCount; ++l)
            correction[l] += g_exact[l] - g[l];
        },
        kRecord | kExact);
    for (Rgb& c : correction)
      c = c / double(corrections);
  }
  for (int l = 0; l < model::kLobeCount; ++l)
    out->lobes[l] += (base[l] + remainder[l]) / area + residual[l] / double(spp) + correction[l];
  out->counters.samples += spp;
  out->counters.visibility_samples += corrections;
  out->counters.texel_evals += spp;
  out->counters.remainder_samples += m;
  return {};
}

}  // namespace clothbake::eval

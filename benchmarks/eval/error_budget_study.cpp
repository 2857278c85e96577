// The error budget of the clustered control variate (docs/evaluator.md, "The error budget"): how
// much of brute force's variance each approximation of the control variate g gives back, switched
// on one at a time, and how g's coupling to the sample decides what is left.
//
// For a footprint P, a light i and a view o, p uniform in P, x'(p) the sample's destination (Eq. 2
// with the per-texel depth) and f the integrand of Eq. 5 at x'(p), a control variate g with an
// exactly known mean leaves the per-sample variance var(f - g); the table reports
// R = var(f) / var(f - g), the variance ratio at equal samples against brute force, and
// E[g] / E[f] - 1, the bias a shading that kept only the base term would have. Stages of g, each
// adding one approximation to the one before, all at the sample's own destination t = x'(p):
//
//   V        f with V(t, i) replaced by the cluster's visibility: the mean v_c(i), or the low-rank
//            form (--ranks) (every lobe: V multiplies all)
//   V,kG     ... and the specular lobe's k(t) G(t) by per-cluster constants: k_c the cluster's mean
//            albedo, G_c Eq. 10's attenuation at a representative fibre (variants below), for
//            this (i, o)
//   V,kG,D   ... and I(t) D_t(h) by the Integral-Radiance table value T(t, h) (binned, 4 bins)
//
// and the couplings of the last g, i.e. where it is evaluated for a sample p:
//
//   bin      x'_k(p) = p + N r_k(q) (v_k,x, v_k,y) / v_k,z: one parallax view bin k drawn with its
//            bilinear weight, its own depth r_k and its centre direction v_k; the mean of g over
//            whole tiles is then a per-bin table (the push-forward of each bin), exact
//   nearest  the same with the bin of largest weight (no extra randomness)
//   4 bins   the weighted sum of g at the four bins' destinations (4 evaluations of g)
//   shift    p + the footprint's mean offset (the unbiased form before format 1.6)
//   split    "bin" on the whole-tile block A of P (the largest block of whole periods at P's
//            corner), "shift" on the rest: what a footprint of any size can integrate exactly
//
// Clusterings: the asset's (its stored v_c grid), the asset's split by yarn (label x yarn id; v_c
// the exact cluster mean of V at i), and those of --ranks and --yarn-ranks.
//   block B  g averaged over the destinations of the B x B source block containing p (drawn bin):
//            a pull-back exactly integrable over any footprint from block prefix sums
//
//   error_budget_study ASSET... [--samples N] [--positions K] [--lobes all|specular|both]
//                               [--sizes a,b,...] [--ranks r,...] [--yarn-ranks r,...]
//                               [--depth-model] [--untilted-g] [--g-per-cluster] [--oracle-g]
//                               [--shipped] [--estimates K] [--detail]
// Defaults are the shipped estimator's choices: f with results interpolated between view bins
// (--depth-model: the depth interpolated, the model before format 1.6), G at the yarn's
// representative fibre turned normal to h (--untilted-g: not turned; --g-per-cluster: the
// cluster's fibre; --oracle-g: the least-squares constant). --ranks adds clusterings split by yarn
// with a visibility basis of these ranks fitted here, --yarn-ranks the same with one cluster per
// yarn. The last section measures the shipped estimator itself (Method::Multiscale against
// Method::Brute at 1 spp, K estimates per pair and position; --shipped: only that section).
// Footprints: the tile and squares of the given sides (default 32,128,384,512), each at K random
// positions (default 8; 1 for whole multiples of the tile). The 16 (i, o) pairs: lights (0,0,1),
// (0.3,0.1,0.95), (0.6,0.3,0.74), (0.85,0.2,0.49) x views (-0.1,0.1,0.99), (-0.4,0.1,0.85),
// (-0.7,0.1,0.7), (0.5,0.5,0.7). Uses the evaluator's internal headers; exit 2 on a bad asset.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "eval/eval_data.hpp"
#include "eval/evaluator.hpp"
#include "eval/texel_shading.hpp"
#include "model/asg.hpp"
#include "model/spongecake.hpp"

using namespace clothbake;
using namespace clothbake::eval;

namespace {

constexpr double kLights[4][3] = {{0, 0, 1}, {0.3, 0.1, 0.95}, {0.6, 0.3, 0.74}, {0.85, 0.2, 0.49}};
constexpr double kViews[4][3] = {
    {-0.1, 0.1, 0.99}, {-0.4, 0.1, 0.85}, {-0.7, 0.1, 0.7}, {0.5, 0.5, 0.7}};

enum Row {
  kV,
  kVkG,
  kVkGD,
  kBin,
  kNearest,
  kFourBins,
  kShift,
  kSplit,
  kBlock1,
  kBlock4,
  kBlock8,
  kBlock16,
  kRows
};
const char* const kRowNames[kRows] = {"V",         "V,kG",      "V,kG,D",    "  at bin",
                                      "  nearest", "  4 bins",  "  shift",   "  split",
                                      "  block 1", "  block 4", "  block 8", "  block 16"};

// A clustering of the texels with the control variate's per-cluster constants.
struct Clustering {
  std::string name;
  std::vector<uint32_t> label;  // per texel
  uint32_t count = 0;
  bool stored_means = false;  // v_c from the asset's grid (else the exact mean of V at i)
  std::vector<Rgb> albedo;    // k_c
  std::vector<model::ClothBsdf<double>> bsdf;  // at the representative texel
  std::vector<uint64_t> representative;
  // Low-rank visibility (rank > 0): V(t, i) ~ mean_c(i) + sum_m coef[t][m] basis[c][m](i), the
  // per-cluster principal components of V(t, l) over the light grid's bin centres l, bilinear in i.
  int rank = 0;
  uint32_t light_dirs = 0;
  std::vector<double> light_mean;   // [c][l]
  std::vector<double> light_basis;  // [c][m][l]
  std::vector<double> coef;         // [t][m]
};

// Fits the per-cluster principal components of the clamped ASG visibility at the light grid's bin
// centres (the asset's visibility grid).
void fit_visibility_basis(const EvalData& d, int rank, Clustering* c) {
  const uint32_t dirs = d.clusters.visibility_dirs(), L = dirs * dirs;
  const uint64_t texels = uint64_t(d.n) * d.n;
  const model::DirectionGrid<double> grid{int(dirs), 0.0};
  std::vector<float> V(texels * L);
  for (uint64_t t = 0; t < texels; ++t) {
    const model::Asg<double> lobe =
        model::asg_from_params(d.visibility.lobe(int64_t(t % d.n), int64_t(t / d.n)));
    for (uint32_t l = 0; l < L; ++l)
      V[t * L + l] = float(std::clamp(
          model::asg_eval(lobe, grid.bin_center(int(l % dirs), int(l / dirs))), 0.0, 1.0));
  }
  c->rank = rank;
  c->light_dirs = dirs;
  c->light_mean.assign(uint64_t(c->count) * L, 0.0);
  c->light_basis.assign(uint64_t(c->count) * rank * L, 0.0);
  c->coef.assign(texels * rank, 0.0);
  for (uint32_t cl = 0; cl < c->count; ++cl) {
    std::vector<uint64_t> members;
    for (uint64_t t = 0; t < texels; ++t)
      if (c->label[t] == cl) members.push_back(t);
    if (members.empty()) continue;
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(L);
    for (uint64_t t : members)
      for (uint32_t l = 0; l < L; ++l)
        mean[l] += V[t * L + l];
    mean /= double(members.size());
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(L, L);
    Eigen::VectorXd row(L);
    for (uint64_t t : members) {
      for (uint32_t l = 0; l < L; ++l)
        row[l] = V[t * L + l] - mean[l];
      cov.selfadjointView<Eigen::Lower>().rankUpdate(row);
    }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov.selfadjointView<Eigen::Lower>());
    for (uint32_t l = 0; l < L; ++l)
      c->light_mean[uint64_t(cl) * L + l] = mean[l];
    for (int m = 0; m < rank; ++m) {
      const Eigen::VectorXd b = eig.eigenvectors().col(L - 1 - m);
      for (uint32_t l = 0; l < L; ++l)
        c->light_basis[(uint64_t(cl) * rank + m) * L + l] = b[l];
      for (uint64_t t : members) {
        double e = 0;
        for (uint32_t l = 0; l < L; ++l)
          e += (V[t * L + l] - mean[l]) * b[l];
        c->coef[t * rank + m] = e;
      }
    }
  }
}

void finish(const EvalData& d, Clustering* c) {
  const uint64_t texels = uint64_t(d.n) * d.n;
  std::vector<double> count(c->count, 0.0);
  std::vector<std::array<double, 7>> mean(c->count, std::array<double, 7>{});
  c->albedo.assign(c->count, Rgb());
  auto fibre = [&](uint64_t t) {
    const float* v = d.maps.tangent.data + 3 * t;
    const double len = std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
    const double x = len > 0 ? v[0] / len : 0, y = len > 0 ? v[1] / len : 0,
                 z = len > 0 ? v[2] / len : 1;
    return std::array<double, 7>{
        x * x, y * y, z * z, x * y, x * z, y * z, d.yarns[d.maps.yarn_id[t]].roughness};
  };
  for (uint64_t t = 0; t < texels; ++t) {
    const uint32_t l = c->label[t];
    const float* colour = d.maps.albedo.data + 3 * t;
    c->albedo[l] +=
        d.yarns[d.maps.yarn_id[t]].specular_albedo * Rgb(colour[0], colour[1], colour[2]);
    count[l] += 1;
    const auto f = fibre(t);
    for (int k = 0; k < 7; ++k)
      mean[l][k] += f[k];
  }
  for (uint32_t l = 0; l < c->count; ++l)
    if (count[l] > 0) {
      c->albedo[l] = c->albedo[l] / count[l];
      for (double& m : mean[l])
        m /= count[l];
    }
  std::vector<double> best(c->count, INFINITY);
  std::vector<uint64_t> rep(c->count, 0);
  for (uint64_t t = 0; t < texels; ++t) {
    const uint32_t l = c->label[t];
    const auto f = fibre(t);
    double dist = 0;
    for (int k = 0; k < 7; ++k)
      dist += (f[k] - mean[l][k]) * (f[k] - mean[l][k]);
    if (dist < best[l]) best[l] = dist, rep[l] = t;
  }
  c->bsdf.clear();
  for (uint32_t l = 0; l < c->count; ++l)
    c->bsdf.emplace_back(d.texel_params(rep[l]));
  c->representative = rep;
}

Clustering asset_clustering(const EvalData& d) {
  Clustering c;
  c.name = "asset clusters";
  c.count = d.cluster_count();
  c.stored_means = true;
  for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t)
    c.label.push_back(d.clusters.label(int64_t(t % d.n), int64_t(t / d.n)));
  finish(d, &c);
  return c;
}

Clustering yarn_split(const EvalData& d) {
  Clustering c;
  c.name = "asset clusters x yarn";
  const uint32_t yarns = uint32_t(d.yarns.size());
  std::vector<int64_t> id(uint64_t(d.cluster_count()) * yarns, -1);
  for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t) {
    const uint64_t key =
        uint64_t(d.clusters.label(int64_t(t % d.n), int64_t(t / d.n))) * yarns + d.maps.yarn_id[t];
    if (id[key] < 0) id[key] = c.count++;
    c.label.push_back(uint32_t(id[key]));
  }
  finish(d, &c);
  return c;
}

Clustering yarn_only(const EvalData& d) {
  Clustering c;
  c.name = "one cluster per yarn";
  c.count = uint32_t(d.yarns.size());
  for (uint64_t t = 0; t < uint64_t(d.n) * d.n; ++t)
    c.label.push_back(d.maps.yarn_id[t]);
  finish(d, &c);
  return c;
}

struct Moments {
  double sum = 0, sum2 = 0;
  void add(double v) { sum += v, sum2 += v * v; }
};

// One (pair, footprint position)'s accumulators: f, and per row f - g and g.
struct Accumulators {
  Moments f, residual[kRows], g[kRows];
  uint64_t n = 0;
};

double variance(const Moments& m, uint64_t n) {
  const double mean = m.sum / double(n);
  return std::max(0.0, m.sum2 / double(n) - mean * mean);
}

struct Config {
  int samples = 20000;
  int positions = 8;
  std::vector<double> sizes = {32, 128, 384, 512};
  bool detail = false;
  int estimates = 4000;         // --estimates: per pair and position, for the shipped section
  bool only_shipped = false;    // --shipped: only the shipped estimator's section
  bool result_model = true;     // results interpolated between view bins (--depth-model: depths)
  std::vector<int> ranks;       // low-rank visibility variants (yarn-split clusters)
  std::vector<int> yarn_ranks;  // the same with one cluster per yarn
};

// Everything of one (pair, clustering, lobe mask) that does not depend on the footprint: per
// texel, f at V = 1, its parts, V, the cluster, and the pulled-back block means of g.
struct PairTables {
  ShadingFrame frame;
  std::vector<double> f1, V, g_kG, g_final;  // g_kG, g_final without v_c ... times v_c below
  std::vector<double> g_V;                   // f1 v_c
  std::vector<double> depth;                 // interpolated r per source texel
  double bin_depth_scale[4][2] = {};         // Eq. 2's factor at bin k's centre
  std::vector<double> bin_r[4];              // r_k per source texel
  int nearest = 0;
  // Block means, per block size and bin: (N/B)^2 values of (1/B^2) sum over the block's texels q
  // of the area-weighted g_final over the unit square at q + delta_k(q).
  std::vector<double> block[4][4];
};
constexpr int kBlockSizes[4] = {1, 4, 8, 16};

// Variants of the control variate's G (the defaults are the shipped estimator's):
bool oracle_g = false;    // --oracle-g: the least-squares k G constant per cluster and (i, o)
bool projected_g = true;  // the representative fibre turned normal to h (--untilted-g: as is)
bool g_per_yarn = true;   // the yarn's representative fibre (--g-per-cluster: the cluster's)

PairTables make_tables(const EvalData& d, const Clustering& cl, const double wi[3],
                       const double wo[3], LobeMask mask) {
  PairTables tb;
  ShadingFrame& frame = tb.frame;
  Status s;
  if (!make_frame(d, wi, wo, mask, &frame, &s)) std::abort();
  const uint32_t n = d.n;
  const uint64_t texels = uint64_t(n) * n;
  tb.V.resize(texels);
  for (uint64_t t = 0; t < texels; ++t)
    tb.V[t] = std::clamp(
        model::asg_eval(model::asg_from_params(d.visibility.lobe(int64_t(t % n), int64_t(t / n))),
                        frame.wi_light),
        0.0, 1.0);
  // v_c(i): the asset's grid means, or the exact mean of the clamped ASG over the cluster.
  std::vector<double> vbar(cl.count, 0.0);
  if (cl.stored_means) {
    for (uint32_t c = 0; c < cl.count; ++c)
      vbar[c] = frame.mean_visibility[c];
  } else {
    std::vector<double> count(cl.count, 0.0);
    for (uint64_t t = 0; t < texels; ++t) {
      vbar[cl.label[t]] += tb.V[t];
      count[cl.label[t]] += 1;
    }
    for (uint32_t c = 0; c < cl.count; ++c)
      vbar[c] = count[c] > 0 ? vbar[c] / count[c] : 0.0;
  }
  // The control variate's visibility per texel: v_c(i), or the low-rank form.
  std::vector<double> vapprox(texels);
  if (cl.rank == 0) {
    for (uint64_t t = 0; t < texels; ++t)
      vapprox[t] = vbar[cl.label[t]];
  } else {
    const model::DirectionGrid<double> grid{int(cl.light_dirs), 0.0};
    const model::BinBilinear<double> b = grid.bilinear(frame.wi_light);
    const uint32_t L = cl.light_dirs * cl.light_dirs;
    std::vector<double> mean(cl.count, 0.0), basis(uint64_t(cl.count) * cl.rank, 0.0);
    for (uint32_t c = 0; c < cl.count; ++c)
      for (int k = 0; k < 4; ++k) {
        mean[c] += b.weight[k] * cl.light_mean[uint64_t(c) * L + uint32_t(b.index[k])];
        for (int m = 0; m < cl.rank; ++m)
          basis[uint64_t(c) * cl.rank + m] +=
              b.weight[k] * cl.light_basis[(uint64_t(c) * cl.rank + m) * L + uint32_t(b.index[k])];
      }
    for (uint64_t t = 0; t < texels; ++t) {
      const uint32_t c = cl.label[t];
      double v = mean[c];
      for (int m = 0; m < cl.rank; ++m)
        v += cl.coef[t * cl.rank + m] * basis[uint64_t(c) * cl.rank + m];
      vapprox[t] = v;
    }
  }
  const bool reflect = frame.wi.z * frame.wo.z > 0;
  const int spec =
      int(reflect ? model::Lobe::SpecularReflection : model::Lobe::SpecularTransmission);
  const bool with_spec = (mask & (1u << spec)) != 0;
  // k_c G_c |i_z| T_sheen per cluster (RGB).
  std::vector<Rgb> spec_scale(cl.count);
  const Rgb t_sheen = cl.bsdf[0].sheen_transmittance(frame.wo);
  for (uint32_t c = 0; c < cl.count; ++c) {
    model::ClothBsdf<double> projected = cl.bsdf[c];
    if (projected_g) {
      // The representative fibre turned into the plane normal to h: the fibres that reflect i
      // into o have t . h = 0.
      model::TexelParams<double> params = d.texel_params(cl.representative[c]);
      const model::Vec3d hn = frame.h * (1.0 / std::sqrt(dot(frame.h, frame.h)));
      model::Vec3d t = params.tangent;
      t = t - hn * dot(t, hn);
      if (dot(t, t) > 1e-12) params.tangent = t;
      projected = model::ClothBsdf<double>(params);
    }
    const auto& b = projected_g ? projected : cl.bsdf[c];
    const double dh = b.sggx().D(frame.h);
    const double fv =
        reflect
            ? model::spongecake_reflection(b.sggx(), b.optical_thickness(), frame.wi, frame.wo)
            : model::spongecake_transmission(b.sggx(), b.optical_thickness(), frame.wi, frame.wo);
    spec_scale[c] = cl.albedo[c] * t_sheen * ((dh > 0 ? fv / dh : 0.0) * frame.cos_i);
  }
  if (oracle_g && with_spec) {
    // The least-squares constant per cluster: sum f_spec I D / sum (I D)^2 over its texels.
    std::vector<double> num(cl.count, 0.0), den(cl.count, 0.0);
    for (uint64_t t = 0; t < texels; ++t) {
      const model::ClothBsdf<double> bsdf(d.texel_params(t));
      Rgb lobes[model::kLobeCount];
      integrand_lobes(frame, bsdf.eval(frame.wi, frame.wo, 1.0), lobes);
      const double id = bsdf.gap() * bsdf.sggx().D(frame.h);
      num[cl.label[t]] += lobes[spec].mean() * id;
      den[cl.label[t]] += id * id;
    }
    for (uint32_t c = 0; c < cl.count; ++c)
      spec_scale[c] = Rgb(den[c] > 0 ? num[c] / den[c] : 0.0);
  }
  reader::BinWeights h_bins;
  const double h[3] = {frame.h.x, frame.h.y, frame.h.z};
  const bool has_bins = reader::make_bin_weights(d.specular.tables->bins_per_side(), h, &h_bins);
  tb.f1.resize(texels);
  tb.g_V.resize(texels);
  tb.g_kG.resize(texels);
  tb.g_final.resize(texels);
  for (uint64_t t = 0; t < texels; ++t) {
    const uint32_t tx = uint32_t(t % n), ty = uint32_t(t / n);
    const model::ClothBsdf<double> bsdf(d.texel_params(t));
    Rgb lobes[model::kLobeCount];
    integrand_lobes(frame, bsdf.eval(frame.wi, frame.wo, 1.0), lobes);
    double f1 = 0, rest1 = 0;
    for (int l = 0; l < model::kLobeCount; ++l) {
      f1 += lobes[l].mean();
      if (l != spec) rest1 += lobes[l].mean();
    }
    const uint32_t c = cl.label[t];
    double kG = 0, table = 0;
    if (with_spec) {
      const double scale = spec_scale[c].mean();
      kG = scale * bsdf.gap() * bsdf.sggx().D(frame.h);
      int cluster = -1;
      const double value =
          has_bins ? d.specular.texel_value(h_bins, tx, ty, d.clusters.label(tx, ty), &cluster)
                   : 0.0;
      table = cluster < 0 ? 0.0 : scale * value;
    }
    tb.f1[t] = f1;
    tb.g_V[t] = f1 * vapprox[t];
    tb.g_kG[t] = (rest1 + kG) * vapprox[t];
    tb.g_final[t] = (rest1 + table) * vapprox[t];
  }
  tb.depth.resize(texels);
  for (uint64_t t = 0; t < texels; ++t)
    tb.depth[t] = texel_depth(d, frame, int64_t(t % n), int64_t(t / n));
  const model::DirectionGrid<double> grid{int(d.parallax.dirs()), d.parallax.info().min_cos};
  for (int k = 0; k < 4; ++k) {
    const int b = frame.parallax_bins.index[k];
    const model::Vec3d v = grid.bin_center(b % grid.n, b / grid.n);
    const double on = d.options.parallax ? double(n) : 0.0;
    tb.bin_depth_scale[k][0] = on * v.x / v.z;
    tb.bin_depth_scale[k][1] = on * v.y / v.z;
    if (frame.parallax_bins.weight[k] > frame.parallax_bins.weight[tb.nearest]) tb.nearest = k;
    tb.bin_r[k].resize(texels);
    for (uint64_t t = 0; t < texels; ++t)
      tb.bin_r[k][t] = d.parallax.bin_depth(uint32_t(b), int64_t(t % n), int64_t(t / n));
  }
  // Pulled-back block means.
  for (int bs = 0; bs < 4; ++bs) {
    const uint32_t B = uint32_t(kBlockSizes[bs]), nb = n / B;
    for (int k = 0; k < 4; ++k) {
      std::vector<double>& out = tb.block[bs][k];
      out.assign(uint64_t(nb) * nb, 0.0);
      for (uint64_t q = 0; q < texels; ++q) {
        const double px = double(q % n) + tb.bin_r[k][q] * tb.bin_depth_scale[k][0];
        const double py = double(q / n) + tb.bin_r[k][q] * tb.bin_depth_scale[k][1];
        const double fx = std::floor(px), fy = std::floor(py);
        const double ax = px - fx, ay = py - fy;
        const int64_t ix = int64_t(fx), iy = int64_t(fy);
        const double v = (1 - ax) * (1 - ay) * tb.g_final[d.texel(ix, iy)] +
                         ax * (1 - ay) * tb.g_final[d.texel(ix + 1, iy)] +
                         (1 - ax) * ay * tb.g_final[d.texel(ix, iy + 1)] +
                         ax * ay * tb.g_final[d.texel(ix + 1, iy + 1)];
        out[uint64_t((q / n) / B) * nb + (q % n) / B] += v / double(B * B);
      }
    }
  }
  return tb;
}

// Samples one footprint with one pair's tables.
void run(const EvalData& d, const PairTables& tb, const Footprint& p, int samples, uint64_t seed,
         bool result_model, Accumulators* acc) {
  const ShadingFrame& frame = tb.frame;
  const double n = d.n;
  // The footprint's mean offset (the parallax SAT's, as multiscale-paper shifts).
  reader::ParallaxSample mean;
  const double view[3] = {frame.view.x, frame.view.y, frame.view.z};
  d.parallax.footprint_depth(p, view, &mean);
  const double sx = mean.offset[0] * n, sy = mean.offset[1] * n;
  // The whole-period block A at P's corner.
  const double ax = std::floor((p.x1 - p.x0) / n) * n, ay = std::floor((p.y1 - p.y0) / n) * n;
  Rng rng(seed);
  for (int k = 0; k < samples; ++k) {
    const double x = p.x0 + rng.uniform() * (p.x1 - p.x0);
    const double y = p.y0 + rng.uniform() * (p.y1 - p.y0);
    const int64_t qx = int64_t(std::floor(x)), qy = int64_t(std::floor(y));
    const uint64_t q = d.texel(qx, qy);
    // One bin drawn with its weight.
    const double u = rng.uniform();
    int drawn = 3;
    double cumulative = 0;
    for (int b = 0; b < 4; ++b) {
      cumulative += frame.parallax_bins.weight[b];
      if (u < cumulative) {
        drawn = b;
        break;
      }
    }
    // The destination: the interpolated depth at the view (the asset's model), or the drawn bin's
    // depth at its centre direction (the model that interpolates results between bins).
    const double r = result_model ? tb.bin_r[drawn][q] : tb.depth[q];
    const double ox = result_model ? tb.bin_depth_scale[drawn][0] : frame.offset_per_depth[0];
    const double oy = result_model ? tb.bin_depth_scale[drawn][1] : frame.offset_per_depth[1];
    const uint64_t t = d.texel(int64_t(std::floor(x + r * ox)), int64_t(std::floor(y + r * oy)));
    const double f = tb.f1[t] * tb.V[t];
    double g[kRows];
    g[kV] = tb.g_V[t];
    g[kVkG] = tb.g_kG[t];
    g[kVkGD] = tb.g_final[t];
    auto at_bin = [&](int b) {
      const double rb = tb.bin_r[b][q];
      return tb.g_final[d.texel(int64_t(std::floor(x + rb * tb.bin_depth_scale[b][0])),
                                int64_t(std::floor(y + rb * tb.bin_depth_scale[b][1])))];
    };
    g[kBin] = at_bin(drawn);
    g[kNearest] = at_bin(tb.nearest);
    g[kFourBins] = 0;
    for (int b = 0; b < 4; ++b)
      if (frame.parallax_bins.weight[b] > 0)
        g[kFourBins] += frame.parallax_bins.weight[b] * at_bin(b);
    g[kShift] = tb.g_final[d.texel(int64_t(std::floor(x + sx)), int64_t(std::floor(y + sy)))];
    const bool in_a = x < p.x0 + ax && y < p.y0 + ay;
    g[kSplit] = in_a ? g[kBin] : g[kShift];
    for (int bs = 0; bs < 4; ++bs) {
      const uint64_t B = uint64_t(kBlockSizes[bs]), nb = uint64_t(n) / B;
      g[kBlock1 + bs] = tb.block[bs][drawn][((q / uint64_t(n)) / B) * nb + (q % uint64_t(n)) / B];
    }
    acc->f.add(f);
    for (int row = 0; row < kRows; ++row) {
      acc->residual[row].add(f - g[row]);
      acc->g[row].add(g[row]);
    }
    ++acc->n;
  }
}

// The footprints of one size: a whole-tile multiple at the origin once (its average does not
// depend on the position), any other size at `positions` random positions (seed 7, the same in
// every section so that their rows are comparable).
std::vector<Footprint> study_footprints(double side, uint32_t n, int positions) {
  const bool periodic = std::fmod(side, double(n)) == 0.0;
  std::vector<Footprint> where(periodic ? 1 : positions);
  Rng place(7);
  for (Footprint& f : where) {
    const double x0 = periodic ? 0.0 : place.uniform() * n;
    const double y0 = periodic ? 0.0 : place.uniform() * n;
    f = Footprint{x0, y0, x0 + side, y0 + side};
  }
  return where;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

void study(const EvalData& d, const Config& cfg, LobeMask mask, const char* lobe_name) {
  std::vector<Clustering> clusterings = {asset_clustering(d), yarn_split(d)};
  const Clustering per_yarn = yarn_only(d);
  for (int rank : cfg.ranks) {
    Clustering c = yarn_split(d);
    if (g_per_yarn)  // G at the yarn's representative fibre (projected normal to h)
      for (uint32_t k = 0; k < c.count; ++k) {
        uint64_t t = 0;
        while (c.label[t] != k)
          ++t;
        c.representative[k] = per_yarn.representative[d.maps.yarn_id[t]];
      }
    fit_visibility_basis(d, rank, &c);
    c.name += ", V of rank " + std::to_string(rank) + " per cluster";
    clusterings.push_back(std::move(c));
  }
  for (int rank : cfg.yarn_ranks) {
    Clustering c = yarn_only(d);
    fit_visibility_basis(d, rank, &c);
    c.name += ", V of rank " + std::to_string(rank) + " per yarn";
    clusterings.push_back(std::move(c));
  }
  std::vector<double> sides = {double(d.n)};
  for (double s : cfg.sizes)
    if (s != d.n) sides.push_back(s);
  for (const Clustering& cl : clusterings) {
    std::vector<PairTables> tables(16);
    {
      auto build = [&](int first, int step) {
        for (int pair = first; pair < 16; pair += step)
          tables[pair] = make_tables(d, cl, kLights[pair / 4], kViews[pair % 4], mask);
      };
      std::thread other(build, 1, 2);
      build(0, 2);
      other.join();
    }
    for (double side : sides) {
      const std::vector<Footprint> where = study_footprints(side, d.n, cfg.positions);
      const int positions = int(where.size());
      {
        // ratios[row][pair], bias[row][pair]
        std::vector<std::vector<double>> ratio(kRows), bias(kRows);
        std::vector<Accumulators> per_pair(16 * positions);
        auto work = [&](int first, int step) {
          for (int pair = first; pair < 16; pair += step) {
            const PairTables& tb = tables[pair];
            for (int pos = 0; pos < positions; ++pos) {
              const int job = pair * positions + pos;
              run(d, tb, where[pos], cfg.samples, uint64_t(job) * 0x9e3779b97f4a7c15ull + 11,
                  cfg.result_model, &per_pair[job]);
            }
          }
        };
        std::thread other(work, 1, 2);
        work(0, 2);
        other.join();
        for (int pair = 0; pair < 16; ++pair) {
          double var_f = 0, mean_f = 0, var_r[kRows] = {}, mean_g[kRows] = {};
          for (int pos = 0; pos < positions; ++pos) {
            const Accumulators& a = per_pair[pair * positions + pos];
            var_f += variance(a.f, a.n);
            mean_f += a.f.sum / double(a.n);
            for (int row = 0; row < kRows; ++row) {
              var_r[row] += variance(a.residual[row], a.n);
              mean_g[row] += a.g[row].sum / double(a.n);
            }
          }
          for (int row = 0; row < kRows; ++row) {
            ratio[row].push_back(var_r[row] > 0 ? var_f / var_r[row] : INFINITY);
            bias[row].push_back(mean_f > 0 ? mean_g[row] / mean_f - 1.0 : 0.0);
          }
        }
        std::printf("\n%s lobes, footprint %g x %g texels (%d position%s), %s\n", lobe_name, side,
                    side, positions, positions > 1 ? "s" : "", cl.name.c_str());
        std::printf("| g | R min | R median | R max | bias median | bias min | bias max |\n");
        std::printf("| --- | --- | --- | --- | --- | --- | --- |\n");
        for (int row = 0; row < kRows; ++row) {
          const auto [rlo, rhi] = std::minmax_element(ratio[row].begin(), ratio[row].end());
          const auto [blo, bhi] = std::minmax_element(bias[row].begin(), bias[row].end());
          std::printf("| %s | %.1f | %.1f | %.1f | %+.3f | %+.3f | %+.3f |\n", kRowNames[row], *rlo,
                      median(ratio[row]), *rhi, median(bias[row]), *blo, *bhi);
        }
        if (cfg.detail)
          for (int pair = 0; pair < 16; ++pair) {
            std::printf("  pair %2d  i (%g, %g, %g) o (%g, %g, %g):", pair, kLights[pair / 4][0],
                        kLights[pair / 4][1], kLights[pair / 4][2], kViews[pair % 4][0],
                        kViews[pair % 4][1], kViews[pair % 4][2]);
            for (int row = 0; row < kRows; ++row)
              std::printf(" %.1f", ratio[row][pair]);
            std::printf("\n");
          }
        std::fflush(stdout);
      }
    }
  }
}

}  // namespace

// The shipped estimator: Method::Multiscale against Method::Brute, both at 1 spp (the per-sample
// variance ratio including the estimator's own remainder samples), and its mean against the
// reference (bias, in standard errors), over the 16 pairs.
void shipped(const Evaluator& ev, const Config& cfg) {
  const EvalData& d = *evaluator_data(ev);
  std::vector<double> sides = {double(d.n)};
  for (double s : cfg.sizes)
    if (s != d.n) sides.push_back(s);
  std::printf(
      "\nthe shipped multiscale estimator at 1 spp against brute force at 1 spp, %d "
      "estimates per pair and position\n",
      cfg.estimates);
  std::printf("| footprint | R min | R median | R max | |bias| / SE max | remainder samples |\n");
  std::printf("| --- | --- | --- | --- | --- | --- |\n");
  for (double side : sides) {
    const std::vector<Footprint> where = study_footprints(side, d.n, cfg.positions);
    const int positions = int(where.size());
    std::vector<double> ratio(16), worst_z(16, 0.0);
    double remainder = 0;
    auto work = [&](int first, int step) {
      for (int pair = first; pair < 16; pair += step) {
        double var_ms = 0, var_brute = 0;
        for (int pos = 0; pos < positions; ++pos) {
          const Footprint& p = where[pos];
          Estimate ref;
          Rng rng(uint64_t(pair) * 131 + uint64_t(pos) + 1);
          if (!ev.estimate(p, kLights[pair / 4], kViews[pair % 4], Method::Reference, 1, rng,
                           kAllLobes, &ref)
                   .ok())
            std::abort();
          Moments ms, brute;
          for (int k = 0; k < cfg.estimates; ++k) {
            Estimate e;
            if (!ev.estimate(p, kLights[pair / 4], kViews[pair % 4], Method::Multiscale, 1, rng,
                             kAllLobes, &e)
                     .ok())
              std::abort();
            ms.add(e.value.mean());
            if (pair == 0) remainder += double(e.counters.remainder_samples);
            if (!ev.estimate(p, kLights[pair / 4], kViews[pair % 4], Method::Brute, 1, rng,
                             kAllLobes, &e)
                     .ok())
              std::abort();
            brute.add(e.value.mean());
          }
          const uint64_t n = uint64_t(cfg.estimates);
          var_ms += variance(ms, n);
          var_brute += variance(brute, n);
          const double se = std::sqrt(variance(ms, n) / double(n));
          const double z = se > 0 ? std::abs(ms.sum / double(n) - ref.value.mean()) / se : 0.0;
          worst_z[pair] = std::max(worst_z[pair], z);
        }
        ratio[pair] = var_ms > 0 ? var_brute / var_ms : INFINITY;
      }
    };
    std::thread other(work, 1, 2);
    work(0, 2);
    other.join();
    const auto [lo, hi] = std::minmax_element(ratio.begin(), ratio.end());
    std::printf("| %g^2 (%d position%s) | %.1f | %.1f | %.1f | %.2f | %.1f |\n", side, positions,
                positions > 1 ? "s" : "", *lo, median(ratio), *hi,
                *std::max_element(worst_z.begin(), worst_z.end()),
                remainder / double(cfg.estimates * positions));
    std::fflush(stdout);
  }
}

int main(int argc, char** argv) {
  Config cfg;
  std::vector<std::string> assets;
  std::string lobes = "both";
  for (int a = 1; a < argc; ++a) {
    const std::string opt = argv[a];
    if (opt == "--detail") {
      cfg.detail = true;
    } else if (opt == "--g-per-cluster") {
      g_per_yarn = false;
    } else if (opt == "--untilted-g") {
      projected_g = false;
    } else if (opt == "--oracle-g") {
      oracle_g = true;
    } else if (opt == "--shipped") {
      cfg.only_shipped = true;
    } else if (opt == "--depth-model") {
      cfg.result_model = false;
    } else if (opt.rfind("--", 0) == 0 && a + 1 < argc) {
      const char* value = argv[++a];
      if (opt == "--samples" && (cfg.samples = std::atoi(value)) > 0) continue;
      if (opt == "--positions" && (cfg.positions = std::atoi(value)) > 0) continue;
      if (opt == "--estimates" && (cfg.estimates = std::atoi(value)) > 1) continue;
      if (opt == "--ranks" || opt == "--yarn-ranks") {
        std::vector<int>& list = opt == "--ranks" ? cfg.ranks : cfg.yarn_ranks;
        for (const char* r = value; *r;) {
          char* end = nullptr;
          const long v = std::strtol(r, &end, 10);
          if (end == r || v < 1 || v > 64) break;
          list.push_back(int(v));
          r = *end == ',' ? end + 1 : end;
        }
        if (!list.empty()) continue;
      }
      if (opt == "--lobes") {
        lobes = value;
        if (lobes == "all" || lobes == "specular" || lobes == "both") continue;
      }
      if (opt == "--sizes") {
        cfg.sizes.clear();
        for (const char* s = value; *s;) {
          char* end = nullptr;
          const double v = std::strtod(s, &end);
          if (end == s || !(v > 0)) break;
          cfg.sizes.push_back(v);
          s = *end == ',' ? end + 1 : end;
        }
        if (!cfg.sizes.empty()) continue;
      }
      std::fprintf(stderr, "error_budget_study: bad option %s %s\n", opt.c_str(), value);
      return 2;
    } else if (opt.rfind("--", 0) == 0) {
      std::fprintf(stderr, "error_budget_study: bad option %s\n", opt.c_str());
      return 2;
    } else {
      assets.push_back(opt);
    }
  }
  if (assets.empty()) {
    std::fprintf(stderr,
                 "usage: error_budget_study ASSET... [--samples N] [--positions K] "
                 "[--lobes all|specular|both] [--sizes a,b,...] [--ranks r,...] "
                 "[--yarn-ranks r,...] [--depth-model] [--untilted-g] [--g-per-cluster] "
                 "[--oracle-g] [--shipped] [--estimates K] [--detail]\n");
    return 2;
  }
  for (const std::string& path : assets) {
    reader::Asset asset;
    Evaluator ev;
    Status s = asset.open_file(path.c_str());
    if (s.ok()) s = ev.open(asset);
    if (!s.ok() || evaluator_data(ev)->specular.tables == nullptr) {
      std::fprintf(stderr, "error_budget_study: %s: %s\n", path.c_str(),
                   s.ok() ? "no Integral-Radiance tables" : s.message());
      return 2;
    }
    const EvalData& d = *evaluator_data(ev);
    std::printf(
        "# %s: %u x %u texels, %u clusters, %u yarns, %u^2 half-vector bins (%s), %d "
        "samples per pair and position\n",
        path.c_str(), d.n, d.n, d.cluster_count(), unsigned(d.yarns.size()),
        d.specular.tables->bins_per_side(), ev.table_source(), cfg.samples);
    if (!cfg.only_shipped) {
      if (lobes != "specular") study(d, cfg, kAllLobes, "all");
      if (lobes != "all")
        study(d, cfg, lobe_bit(model::Lobe::SpecularReflection), "specular reflection");
    }
    shipped(ev, cfg);
  }
  return 0;
}

// The multi-scale evaluator (paper Sec. 4, Eq. 5-11): the average of the cloth BSDF over a pixel
// footprint, as a renderer needs it per shading point, by four methods that estimate the same
// integral (docs/evaluator.md has every formula and the reasoning behind each choice).
//
//   value(P, i, o) = (1/|P|) integral over P of f^(x'(p), i, o) V(x'(p), i) |i_z| dp       (Eq. 5)
//
// P is a footprint rectangle in texel units (any size and position; the tile wraps). The parallax
// interpolates results between the four view bins of the table nearest to o: with their bilinear
// weights w_k, value = sum_k w_k (average over P of the integrand at x'_k(p)), x'_k(p) Eq. 2
// applied to p with bin k's depth of the texel containing p and bin k's centre direction. Every
// other factor (the BSDF parameters of Eq. 4, the ASG visibility V) is that of the texel containing
// x'. The delta transmission lobe is a Dirac term: it contributes its footprint-averaged weight
// exactly when i = -o, and 0 otherwise.
//
// Methods (Method):
//   Multiscale      clustered control variates with each texel's low-rank visibility, at each
//                   sample's own destination, whose mean over a block of whole periods or of whole
//                   source blocks is exact (per-view-bin push-forward sums) and over the rest of
//                   the footprint sampled cheaply, or below a repeat each texel's own control
//                   variate g_V by cheap samples alone: unbiased at every footprint size
//                   (docs/evaluator.md, "Unbiased multi-scale", "Footprints below a period");
//                   footprints below 2 texels a side are sampled as brute force.
//   MultiscalePaper Eq. 8-10 as printed: one parallax shift per footprint, k-bar and G-bar at the
//                   footprint, residual D (V - v_c) (biased where those approximations fail).
//   Brute           the paper's "w/o multi-scale": stratified samples p in P, per-sample parallax,
//                   the full f^ V |i_z| at x'(p).
//   Reference       the exact integral under the piecewise-constant texel model the asset stores
//                   (an exact partition of P into pieces on which the integrand is constant); the
//                   ground truth of every error the project reports.
// The two multi-scale methods answer footprints whose both sides are below
// EvalOptions::direct_max_side texels by the reference's exact sum (no tables, no noise), and
// every method but Brute answers a footprint of area below 1e-12 texel^2 (a point) so; Brute
// samples it.
//
// Contract: C++17, standard library only, over the reader library and model/. Every allocation,
// open()'s and estimate()'s below, comes from EvalOptions::allocator (the asset's when null; the
// reader's decoded maps and tables from the asset's). open() allocates the derived footprint sums
// (docs/evaluator.md, "Memory") and never throws: allocation failure is a Status. estimate()
// allocates only on first use or for large footprints (docs/evaluator.md, "Allocation in
// estimate()"): the Reference method's dense weight map of N x N doubles for footprints of more
// than 64 source texels, the unbiased form's push-forward sums and block prefix sums of a view bin
// on its first use (together at most EvalOptions::max_block_sum_bytes plus about 20 KB a bin), and
// in the reader a compressed parallax table's per-direction SAT (MultiscalePaper's footprint mean)
// or an entropy-coded direction's decoded plane; and, per estimate of the unbiased form, one array
// of the compressed tables' image values at the half vector when they hold more than 1 024 images
// (the satin's 1 420 do; fewer live on the stack). A failed map, sum, SAT or array is Unsupported.
// One failure is silent: a compressed parallax direction whose plane cannot be decoded (its
// allocation fails, or its block is damaged in an asset opened without validation) contributes
// depth 0 to the per-texel depths that need it, so those samples see less parallax. It is noexcept,
// thread-safe (const), and safe for any argument values (bad ones give InvalidArgument). The Asset
// must outlive the Evaluator.
#pragma once

#include <cstdint>
#include <memory>

#include "formats/reader/asset.hpp"
#include "formats/reader/radiance_query.hpp"
#include "formats/reader/status.hpp"
#include "model/cloth_bsdf.hpp"
#include "model/rgb.hpp"
#include "model/splitmix64.hpp"

namespace clothbake::eval {

using Rgb = model::Rgb<double>;
using reader::Footprint;
using reader::Status;

enum class Method : uint8_t { Multiscale, MultiscalePaper, Brute, Reference };
inline constexpr int kMethodCount = 4;

// "multiscale", "multiscale-paper", "brute", "reference".
const char* method_name(Method method) noexcept;
#ifndef CLOTHBAKE_SINGLE_FILE  // for command lines; the C interface numbers its methods
// Inverse of method_name; false for anything else.
bool parse_method(const char* name, Method* out) noexcept;
#endif

// A set of lobes of Eq. 4 (bit = model::Lobe value).
using LobeMask = uint32_t;
inline constexpr LobeMask kAllLobes = (1u << model::kLobeCount) - 1;
constexpr LobeMask lobe_bit(model::Lobe lobe) {
  return 1u << unsigned(lobe);
}

// Which Integral-Radiance tables the multi-scale methods read.
enum class TableChoice : uint8_t {
  Auto,        // the compressed tables when the asset has them, else the raw ones
  Raw,         // the raw fixed-point SATs (NotFound if absent)
  Compressed,  // the C-PCA compressed tables (NotFound if absent)
};

// The base region of the unbiased multi-scale form (EvalOptions::footprint_base).
enum class FootprintBase : uint8_t {
  Auto,          // per footprint, the base form that leaves the smaller remainder, or no base
  WholePeriods,  // whole tiles at the footprint's corner: exact for the full control variate
  Blocks,        // the rectangle of whole source blocks nearest to the footprint
  None,          // no base: the integral of g_V over the footprint by cheap samples alone
};

struct EvalOptions {
  TableChoice tables = TableChoice::Auto;
  // Footprints with both sides below this many texels skip the tables and are summed exactly
  // (`clothbake verify` reports the smallest side at which the compressed tables meet their error
  // target; 1 texel on the example fabrics). 0 disables the direct path.
  double direct_max_side = 1.0;
  // false: the model without parallax (x'(p) = p, no footprint shift): for measuring what the
  // parallax offsets are worth (the near-field report, docs/rendering.md).
  bool parallax = true;
  // The unbiased multi-scale form's cheap samples of g over the part B of a footprint that its
  // block of whole periods leaves (docs/evaluator.md, "Unbiased multi-scale"): ceil(scale (|B| /
  // |P|) sqrt(spp (spp + 2))) of them, at least 1 when B is not empty, at most 65536. Any value > 0
  // keeps the estimate unbiased; this one balances their cost against their variance.
  double remainder_sample_scale = 32.0;
  // The unbiased multi-scale form's visibility correction (docs/evaluator.md, "Unbiased
  // multi-scale", step 6): per residual sample, this many more samples of g with the texel's own
  // visibility V(t, i) less g with its low-rank v(t), stratified over the footprint, and the
  // residual taken against g with V. They need no BSDF evaluation, and V - v is most of f - g where
  // the light grazes the relief. 0 disables it (the residual is f - g with v). Any value keeps the
  // estimate unbiased; at most 1024.
  uint32_t visibility_samples = 8;
  // Whether open() decides, per band of light elevation, if the visibility correction pays for
  // this asset (a pilot of fixed seed at open: the correction where it removes at least a third
  // of the residual's variance, docs/evaluator.md, "Where the correction pays"); false: wherever
  // visibility_samples > 0. Only the forms with a base have the correction. Either keeps the
  // estimate unbiased.
  bool visibility_pilot = true;
  // The unbiased multi-scale form integrates its control variate exactly over whole periods or
  // whole source blocks of a footprint P when the effective remainder that base leaves to cheap
  // samples (eval/footprint_cover.hpp: the part of P outside the exactly integrated base, weighted
  // by its integrand's spread and cost) is at most this fraction of |P|; above it, P takes the form
  // without a base, whose control variate g_V (each texel's own visibility, fibre distribution and
  // albedo) follows f more closely than any g with one but is integrated by cheap samples alone.
  // Any value keeps the estimate unbiased; docs/evaluator.md gives the measured choice.
  double max_remainder_fraction = 0.6;
  // Footprints whose geometric mean side (the square root of their area) is below this many
  // texels are sampled as brute force by the unbiased multi-scale form: over so few texels brute
  // force's stratified samples already see most of the integrand, and the control variate's
  // per-estimate cost does not pay (docs/evaluator.md, "Footprints the control variate does not
  // pay for", gives the measured crossover). 0: no bound.
  double min_control_variate_side = 2.0;
  // The specular attenuation of the control variate g_V in reflection (docs/evaluator.md, "The
  // attenuation g_V takes"): true: per band of min(|i_z|, |o_z|), its yarn's (the yarn's fibre
  // turned normal to h, as g's) or each texel's own (f's, Eq. 10 at the texel's tangent: a closer
  // g_V that costs about a quarter more per estimate without a base), as a pilot at open measures
  // pays; false: its yarn's everywhere. Either keeps the estimate unbiased.
  bool attenuation_pilot = true;
  // The base region of the unbiased multi-scale form (eval/footprint_cover.hpp): Auto takes, per
  // footprint, whichever of whole periods and whole source blocks leaves the smaller remainder,
  // and no base above max_remainder_fraction; the others force one form (for studies:
  // docs/evaluator.md, "Footprints below a period").
  FootprintBase footprint_base = FootprintBase::Auto;
  // The block form's per-bin sums (eval/subperiod_sums.hpp) over every view bin of the parallax
  // table together stay within this many bytes: the evaluator takes the finest block grid (at most
  // 16 x 16 blocks a tile) that fits, and none (no block form) when even 2 x 2 does not. 0
  // disables the block form. Memory is allocated only for the view bins a render meets; larger
  // grids measured slower, their sums missing the caches (docs/evaluator.md).
  double max_block_sum_bytes = double(uint64_t(256) << 20);
  // The visibility rank r of the block sums (the asset's basis rank M when above it, the
  // default): the interior of a block-form footprint samples g - g_r, which is 0 at r = M; a lower
  // rank holds fewer channels per block, (images + 8 C)(r + 1), hence finer blocks within
  // max_block_sum_bytes, for more cheap samples (docs/evaluator.md gives the measured choice).
  uint32_t block_sum_rank = UINT32_MAX;
  // The sheen table of every texel's BSDF (model/sheen.hpp, docs/sheen.md): the published one of
  // Zeltner et al. by default, as renderers ship it; Converged for the layer's exact albedo. The
  // asset stores only the sheen colour and roughness, so this is the evaluator's choice.
  model::SheenConvention sheen_convention = model::SheenConvention::Published;
  // Where open() and the sums built on first use get their memory (model/memory.hpp): the asset's
  // allocator when null. It must outlive the evaluator.
  const model::Allocator* allocator = nullptr;
};

// The random source of the sampling methods: the project's SplitMix64 (model/splitmix64.hpp), bit
// for bit the same on every platform, so that a seed gives the same estimates everywhere.
using Rng = model::SplitMix64;

// What one estimate cost.
struct Counters {
  uint32_t samples = 0;            // Monte Carlo samples drawn over the footprint
  uint32_t texel_evals = 0;        // per-texel BSDF evaluations (f^ V at one texel)
  uint32_t table_queries = 0;      // footprint queries on SATs (radiance, parallax, footprint sums)
  uint32_t remainder_samples = 0;  // multiscale: cheap samples of g outside its exact base
  uint32_t visibility_samples = 0;  // multiscale: samples of the visibility correction
  bool direct = false;              // answered by the exact sum (footprint below direct_max_side)
  bool without_control_variate = false;  // multiscale: sampled as brute force (a footprint below
                                         // EvalOptions::min_control_variate_side)
};

struct Estimate {
  Rgb value;                     // the footprint average of Eq. 5 over the lobes asked for
  Rgb lobes[model::kLobeCount];  // its part per lobe (model::Lobe order); 0 for lobes not asked
  Counters counters;
};

struct EvalData;  // the asset's views and derived tables (eval/eval_data.hpp)

class Evaluator {
 public:
  Evaluator() noexcept;
  ~Evaluator();
  Evaluator(Evaluator&&) noexcept;
  Evaluator& operator=(Evaluator&&) noexcept;

  // Opens the views every method needs and builds the derived footprint sums. Needs the feature
  // maps, fabric records, parallax table with its SAT, visibility ASGs and clusters; the
  // Integral-Radiance specular tables are optional here (the multi-scale methods report NotFound
  // without them). Errors: the reader's (NotFound CBK-E019 naming the missing section, layout and
  // range errors), CrossSection (CBK-E022) when the sections disagree on the resolution or the
  // clusters, Unsupported when the derived tables cannot be allocated.
  Status open(const reader::Asset& asset, const EvalOptions& options = {}) noexcept;
  bool is_open() const noexcept { return data_ != nullptr; }

  uint32_t resolution() const noexcept;
#ifndef CLOTHBAKE_SINGLE_FILE  // reports of the C++ interface, which the C interface leaves out
  uint32_t cluster_count() const noexcept;
  // Which tables the multi-scale methods read: "raw", "compressed" or "none".
  const char* table_source() const noexcept;
  // Bytes of the derived footprint sums held by open().
  uint64_t derived_bytes() const noexcept;
#endif

  // One estimate of the footprint average of Eq. 5 (header comment). wi (towards the light) and wo
  // (towards the viewer) are any finite non-zero vectors in the local frame (normalised here);
  // spp >= 1 samples for the sampling methods (ignored by Reference and by the direct path); rng
  // advances. Errors: InvalidArgument for a bad footprint, direction, spp or lobe mask (0 or
  // unknown bits), NotFound when the method needs tables the asset does not have, Unsupported when
  // a dense weight map or a parallax SAT cannot be allocated (header comment), OutOfPlan when a
  // scene-planned asset left out what the query needs.
  Status estimate(const Footprint& footprint, const double wi[3], const double wo[3], Method method,
                  uint32_t spp, Rng& rng, LobeMask lobes, Estimate* out) const noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE  // for the project's tests and references; not in the single file
  // The Reference method with s x s midpoint samples per covered source texel instead of the exact
  // partition (s >= 1): converges to Reference at |difference| <= max_t f(t) / s per channel, f(t)
  // the integrand of texel t summed over the lobes asked for (docs/evaluator.md, "Reference"); for
  // testing that bound.
  Status reference_supersampled(const Footprint& footprint, const double wi[3], const double wo[3],
                                uint32_t s, LobeMask lobes, Estimate* out) const noexcept;
#endif

  // Importance sampling for a renderer's BSDF samples (Sec. 5.1, multiple importance sampling): the
  // lobe mixture of model::ClothBsdf at the footprint's representative texel, the one at the centre
  // of the footprint shifted by its mean parallax offset (the texel at x'(p0) for a zero-area
  // footprint); for a footprint with area, in a tile with both yarn and gaps, its technique
  // probabilities mixed 3:1 with those of the same texel half in a gap, so that a footprint
  // centred on yarn can draw the delta lobe through the gaps it covers and one centred on a gap its
  // yarns' lobes. A density gives unbiased estimates where it is positive wherever the footprint's
  // f^ is; this one follows the footprint's centre.
  // u_lobe, u1, u2 uniform in [0, 1). out->valid is false when f^ is 0 for wo; a delta sample has
  // wi = -wo and pdf = the discrete probability of the delta technique. Errors as estimate().
  struct DirectionSample {
    bool valid = false;
    bool is_delta = false;
    double wi[3] = {0, 0, 1};
    double pdf = 0;  // solid-angle density of the continuous techniques, or P(delta)
  };
  Status sample_direction(const Footprint& footprint, const double wo[3], double u_lobe, double u1,
                          double u2, DirectionSample* out) const noexcept;
  // The solid-angle density of sample_direction's continuous techniques at wi (it integrates to
  // 1 - P(delta)).
  Status direction_pdf(const Footprint& footprint, const double wi[3], const double wo[3],
                       double* out) const noexcept;

#ifndef CLOTHBAKE_SINGLE_FILE
  // The integrand of Eq. 5 at one texel (x, y) (any integers: the tile wraps) for a visibility
  // given by the caller instead of the stored ASG: f^(x, i, o) V |i_z| over the lobes of the mask
  // (delta: its weight when i = -o). For ray-traced references whose visibility comes from real
  // shadow rays. Errors: InvalidArgument for bad directions, mask or visibility outside [0, 1].
  Status texel_value(int64_t x, int64_t y, const double wi[3], const double wo[3],
                     double visibility, LobeMask lobes, Rgb* out) const noexcept;
#endif

 private:
  // The internal views and derived tables, for the project's own tests and studies only
  // (eval/eval_data.hpp, not installed).
  friend const EvalData* evaluator_data(const Evaluator& evaluator) noexcept;
  struct Release {  // gives EvalData back to the allocator it came from
    void operator()(EvalData* data) const noexcept;
  };
  std::unique_ptr<EvalData, Release> data_;
};

}  // namespace clothbake::eval

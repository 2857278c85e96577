// Evaluator: opening an asset for evaluation and dispatching estimates (evaluator.hpp).
#include "eval/evaluator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <new>

#include "eval/eval_data.hpp"
#include "eval/exact_sum.hpp"
#include "eval/methods.hpp"
#include "eval/visibility_pilot.hpp"

namespace clothbake::eval {
namespace {

using reader::Check;
using reader::ErrorCode;

#ifndef CLOTHBAKE_SINGLE_FILE
// Largest derived footprint sums open() builds (bounds (N + 1)^2 x (3 + 8 C) doubles).
constexpr uint64_t kMaxDerivedBytes = uint64_t(1) << 30;
#endif

const char* const kMethodNames[kMethodCount] = {"multiscale", "multiscale-paper", "brute",
                                                "reference"};

// Opens one kind of Integral-Radiance tables as `choice` asks. Absent tables leave source empty and
// return Ok unless `choice` names a representation explicitly.
Status open_tables(const reader::Asset& asset, reader::RadianceTableKind kind, TableChoice choice,
                   TableSource* source) {
  source->tables = nullptr;
  if (choice != TableChoice::Raw) {
    Status s = source->compressed.open(asset, kind);
    if (s.ok()) {
      source->tables = &source->compressed;
      return {};
    }
    if (s.code() != ErrorCode::NotFound || choice == TableChoice::Compressed) return s;
  }
#ifndef CLOTHBAKE_SINGLE_FILE
  Status s = source->raw.open(asset, kind);
  if (s.ok()) {
    source->tables = &source->raw;
    return {};
  }
  if (s.code() == ErrorCode::NotFound && choice == TableChoice::Auto) return {};
  return s;
#else
  // The single file reads no raw tables (docs/integration.md, "One source file").
  if (choice == TableChoice::Auto) return {};
  return Status::error(ErrorCode::Unsupported, Check::None,
                       "raw Integral-Radiance tables are not read by the single-file build");
#endif
}

Status cross_section(const char* what, uint32_t got, uint32_t want) {
  return Status::error(ErrorCode::Malformed, Check::CrossSection,
                       "%s is %u, the feature maps' resolution or the clusters' count is %u", what,
                       unsigned(got), unsigned(want));
}

}  // namespace

const char* method_name(Method method) noexcept {
  const int m = int(method);
  return m >= 0 && m < kMethodCount ? kMethodNames[m] : "unknown";
}

#ifndef CLOTHBAKE_SINGLE_FILE
bool parse_method(const char* name, Method* out) noexcept {
  if (name == nullptr) return false;
  for (int m = 0; m < kMethodCount; ++m)
    if (std::strcmp(name, kMethodNames[m]) == 0) {
      *out = Method(m);
      return true;
    }
  return false;
}
#endif

void Evaluator::Release::operator()(EvalData* data) const noexcept {
  if (data != nullptr) model::destroy_object(*data->allocator, data);
}

Evaluator::Evaluator() noexcept = default;
Evaluator::~Evaluator() = default;
Evaluator::Evaluator(Evaluator&&) noexcept = default;
Evaluator& Evaluator::operator=(Evaluator&&) noexcept = default;

uint32_t Evaluator::resolution() const noexcept {
  return data_ ? data_->n : 0;
}
#ifndef CLOTHBAKE_SINGLE_FILE
uint32_t Evaluator::cluster_count() const noexcept {
  return data_ ? data_->cluster_count() : 0;
}
const char* Evaluator::table_source() const noexcept {
  if (!data_ || !data_->specular.present()) return "none";
  return data_->specular.is_compressed() ? "compressed" : "raw";
}
uint64_t Evaluator::derived_bytes() const noexcept {
  return data_ ? data_->sums.bytes() : 0;
}
#endif

Status Evaluator::open(const reader::Asset& asset, const EvalOptions& options) noexcept {
  data_.reset();
  if (options.visibility_samples > 1024)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "visibility_samples must be at most 1024");
  if (!(options.remainder_sample_scale > 0.0) || !std::isfinite(options.remainder_sample_scale))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "remainder_sample_scale must be finite and > 0");
  if (!(options.max_remainder_fraction >= 0.0) || !std::isfinite(options.max_remainder_fraction))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "max_remainder_fraction must be finite and >= 0");
  if (!(options.max_block_sum_bytes >= 0.0) || std::isnan(options.max_block_sum_bytes))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "max_block_sum_bytes must be >= 0");
  if (unsigned(options.footprint_base) > unsigned(FootprintBase::None))
    return Status::error(ErrorCode::InvalidArgument, Check::None, "unknown footprint_base");
  if (!(options.min_control_variate_side >= 0.0) ||
      !std::isfinite(options.min_control_variate_side))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "min_control_variate_side must be finite and >= 0");
  if (!(options.direct_max_side >= 0.0) || !std::isfinite(options.direct_max_side))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "direct_max_side must be finite and >= 0");
  const model::Allocator* allocator =
      options.allocator != nullptr ? options.allocator : asset.allocator();
  std::unique_ptr<EvalData, Release> d(model::create_object<EvalData>(*allocator));
  if (!d) return Status::error(ErrorCode::Unsupported, Check::None, "cannot allocate");
  d->options = options;
  d->allocator = allocator;

  Status s = reader::read_feature_maps(asset, &d->maps);
  if (!s.ok()) return s;
  d->n = d->maps.resolution;
  const reader::FabricInfoRecord* fabric = nullptr;
  s = reader::read_fabric_info(asset, &fabric);
  if (!s.ok()) return s;
  reader::ArrayView<reader::YarnMaterialRecord> yarns;
  s = reader::read_yarn_materials(asset, &yarns);
  if (!s.ok()) return s;
  if (yarns.size == 0)
    return Status::error(ErrorCode::Malformed, Check::YarnIdRange, "the asset has no yarn records");
  if (!d->yarns.allocate(yarns.size, allocator))
    return Status::error(ErrorCode::Unsupported, Check::None, "cannot allocate the yarn table");
  for (uint64_t k = 0; k < yarns.size; ++k) {
    const reader::YarnMaterialRecord& r = yarns[k];
    YarnShading& y = d->yarns[k];
    y.roughness = r.roughness;
    y.sggx = model::FibreSggx<double>::make(model::Vec3d(0, 0, 1), r.roughness);
    y.optical_thickness = r.optical_thickness;
    y.specular_albedo = Rgb(r.specular_albedo[0], r.specular_albedo[1], r.specular_albedo[2]);
    y.diffuse_reflectance =
        Rgb(r.diffuse_reflectance[0], r.diffuse_reflectance[1], r.diffuse_reflectance[2]);
    y.diffuse_transmittance =
        Rgb(r.diffuse_transmittance[0], r.diffuse_transmittance[1], r.diffuse_transmittance[2]);
  }
  for (uint64_t t = 0; t < d->maps.yarn_id.size; ++t)
    if (d->maps.yarn_id[t] >= yarns.size)
      return Status::error(ErrorCode::Malformed, Check::YarnIdRange,
                           "texel (%u, %u) has yarn id %u but the asset has %u yarn records",
                           unsigned(t % d->n), unsigned(t / d->n), unsigned(d->maps.yarn_id[t]),
                           unsigned(yarns.size));
  d->sheen_color = Rgb(fabric->sheen_color[0], fabric->sheen_color[1], fabric->sheen_color[2]);
  d->sheen_roughness = fabric->sheen_roughness;

  s = d->parallax.open(asset);
  if (!s.ok()) return s;
  s = reader::read_scene_plan(asset, &d->plan, &d->planned);
  if (!s.ok()) return s;
  if (!d->parallax.has_sat())
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "this asset has no parallax_sat section (the evaluator needs the "
                         "footprint-averaged offsets)");
  s = d->visibility.open(asset);
  if (!s.ok()) return s;
  s = d->clusters.open(asset);
  if (!s.ok()) return s;
  if (d->parallax.resolution() != d->n)
    return cross_section("parallax resolution", d->parallax.resolution(), d->n);
  if (d->visibility.resolution() != d->n)
    return cross_section("visibility resolution", d->visibility.resolution(), d->n);
  if (d->clusters.resolution() != d->n)
    return cross_section("cluster label resolution", d->clusters.resolution(), d->n);

  const uint32_t clusters = d->cluster_count();
  s = open_tables(asset, reader::RadianceTableKind::Specular, options.tables, &d->specular);
  if (!s.ok()) return s;
  const TableChoice gap_choice =
      d->specular.present()
          ? (d->specular.is_compressed() ? TableChoice::Compressed : TableChoice::Raw)
          : options.tables;
  s = open_tables(asset, reader::RadianceTableKind::Gap, gap_choice, &d->gap);
  if (s.code() == ErrorCode::NotFound) {
    d->gap.tables = nullptr;  // no gap tables in this representation: the footprint sums stand in
    s = {};
  }
  if (!s.ok()) return s;
  for (const TableSource* source : {&d->specular, &d->gap}) {
    if (!source->present()) continue;
    if (source->tables->resolution() != d->n)
      return cross_section("Integral-Radiance table resolution", source->tables->resolution(),
                           d->n);
    if (source->tables->cluster_count() != clusters)
      return cross_section("Integral-Radiance cluster count", source->tables->cluster_count(),
                           clusters);
  }

#ifndef CLOTHBAKE_SINGLE_FILE
  const SumChannels layout{clusters};
  if (uint64_t(d->n + 1) * (d->n + 1) * layout.count() * sizeof(double) > kMaxDerivedBytes)
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "the footprint sums of %u x %u texels and %u clusters exceed %llu bytes",
                         unsigned(d->n), unsigned(d->n), unsigned(clusters),
                         static_cast<unsigned long long>(kMaxDerivedBytes));
  const EvalData& data = *d;
  const bool built = d->sums.build(
      d->n, layout,
      [&](uint64_t t, double* out) {
        for (uint32_t c = 0; c < layout.count(); ++c)
          out[c] = 0.0;
        const uint32_t label = data.clusters.label(int64_t(t % data.n), int64_t(t / data.n));
        const YarnShading& yarn = data.yarns[data.maps.yarn_id[t]];
        const float* colour = data.maps.albedo.data + 3 * t;
        const Rgb c(colour[0], colour[1], colour[2]);
        const double gap = data.maps.gap[t];
        const Rgb k = yarn.specular_albedo * c;
        const Rgb rd = (yarn.diffuse_reflectance * c) * gap;
        const Rgb td = (yarn.diffuse_transmittance * c) * gap;
        for (int ch = 0; ch < 3; ++ch) {
          out[layout.albedo() + ch] = k[ch];
          out[layout.diffuse_r() + 3 * label + ch] = rd[ch];
          out[layout.diffuse_t() + 3 * label + ch] = td[ch];
        }
        out[layout.area() + label] = 1.0;
        out[layout.gap() + label] = 1.0 - gap;
      },
      allocator);
  if (!built)
    return Status::error(ErrorCode::Unsupported, Check::None, "cannot allocate the footprint sums");
#endif
  // The visibility basis: optional; it must describe the label map's clusters.
  s = d->basis.open(asset);
  if (s.code() == ErrorCode::NotFound) {
    d->basis = reader::VisibilityBasisView();
    s = {};
  }
  if (!s.ok()) return s;
  if (d->basis.is_open()) {
    if (d->basis.cluster_count() != clusters)
      return cross_section("cluster_visibility_basis cluster count", d->basis.cluster_count(),
                           clusters);
    if (d->basis.rank() > 0 && d->basis.resolution() != d->n)
      return cross_section("cluster_visibility_basis resolution", d->basis.resolution(), d->n);
  }
  // Each cluster's mean specular albedo over the tile and its most frequent yarn: the per-cluster
  // constants of the unbiased control variate.
  const uint64_t texels = uint64_t(d->n) * d->n;
  const uint32_t yarn_count = uint32_t(d->yarns.size());
  const Status out_of_memory = Status::error(ErrorCode::Unsupported, Check::None,
                                             "cannot allocate the control variate's constants");
  model::Buffer<double> count;  // zero-filled, as every Buffer below
  model::Buffer<uint64_t> cluster_yarn_count;
  model::Buffer<std::array<double, 7>> mean;
  model::Buffer<double> yarn_texels, best;
  model::Buffer<uint64_t> representative;
  if (!count.allocate(clusters, allocator) ||
      !cluster_yarn_count.allocate(uint64_t(clusters) * yarn_count, allocator) ||
      !d->cluster_albedo.allocate(clusters, allocator) ||
      !d->cluster_yarn.allocate(clusters, allocator) || !mean.allocate(yarn_count, allocator) ||
      !yarn_texels.allocate(yarn_count, allocator) ||
      !best.assign(yarn_count, INFINITY, allocator) ||
      !representative.allocate(yarn_count, allocator) ||
      !d->yarn_fibre.allocate(yarn_count, allocator))
    return out_of_memory;
  for (uint64_t t = 0; t < texels; ++t) {
    const uint32_t label = d->clusters.label(int64_t(t % d->n), int64_t(t / d->n));
    const float* colour = d->maps.albedo.data + 3 * t;
    d->cluster_albedo[label] +=
        d->yarns[d->maps.yarn_id[t]].specular_albedo * Rgb(colour[0], colour[1], colour[2]);
    count[label] += 1.0;
    ++cluster_yarn_count[uint64_t(label) * yarn_count + d->maps.yarn_id[t]];
  }
  for (uint32_t c = 0; c < clusters; ++c) {
    if (count[c] > 0) d->cluster_albedo[c] = d->cluster_albedo[c] / count[c];
    const uint64_t* row = &cluster_yarn_count[uint64_t(c) * yarn_count];
    d->cluster_yarn[c] = uint32_t(std::max_element(row, row + yarn_count) - row);
  }
  // The representative texel of each yarn: nearest to the yarn's mean of (t t^T, roughness),
  // t t^T being the sign-free description of a fibre line.
  auto fibre = [&](uint64_t t) {
    const float* v = d->maps.tangent.data + 3 * t;
    const double len = std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
    const double x = len > 0 ? v[0] / len : 0, y = len > 0 ? v[1] / len : 0,
                 z = len > 0 ? v[2] / len : 1;
    return std::array<double, 7>{
        x * x, y * y, z * z, x * y, x * z, y * z, d->yarns[d->maps.yarn_id[t]].roughness};
  };
  for (uint64_t t = 0; t < texels; ++t) {
    const auto f = fibre(t);
    const uint32_t y = d->maps.yarn_id[t];
    for (int k = 0; k < 7; ++k)
      mean[y][k] += f[k];
    yarn_texels[y] += 1.0;
    d->has_gaps |= d->maps.gap[t] < 1.0f;
    d->has_yarn |= d->maps.gap[t] > 0.0f;
  }
  for (uint32_t y = 0; y < yarn_count; ++y)
    for (double& m : mean[y])
      m /= std::max(yarn_texels[y], 1.0);
  for (uint64_t t = 0; t < texels; ++t) {
    const uint32_t y = d->maps.yarn_id[t];
    const auto f = fibre(t);
    double dist = 0;
    for (int k = 0; k < 7; ++k)
      dist += (f[k] - mean[y][k]) * (f[k] - mean[y][k]);
    if (dist < best[y]) best[y] = dist, representative[y] = t;
  }
  for (uint32_t y = 0; y < yarn_count; ++y)
    d->yarn_fibre[y] = d->texel_params(representative[y]);
  // The unbiased form's push-forward sums (compressed specular tables only).
  if (d->specular.present() && d->specular.is_compressed()) {
    const reader::CompressedRadianceTables& tables = d->specular.compressed;
    if (!d->image_cluster.allocate(tables.image_count(), allocator) ||
        !d->cluster_image_begin.allocate(clusters + 1, allocator))
      return out_of_memory;
    for (uint32_t i = 0; i < tables.image_count(); ++i)
      d->image_cluster[i] = tables.image_cluster(i);
    for (uint32_t i = 0; i < tables.image_count(); ++i)  // image_cluster is non-decreasing
      d->cluster_image_begin[d->image_cluster[i] + 1] = i + 1;
    for (uint32_t c = 0; c < clusters; ++c)
      d->cluster_image_begin[c + 1] =
          std::max(d->cluster_image_begin[c + 1], d->cluster_image_begin[c]);
    PushforwardChannels layout;
    layout.images = tables.image_count();
    layout.clusters = clusters;
    layout.rank = d->visibility_rank();
    if (!d->pushforward.init(d.get(), d->parallax.dirs() * d->parallax.dirs(), layout))
      return Status::error(ErrorCode::Unsupported, Check::None,
                           "cannot allocate the push-forward bookkeeping");
    if (!d->cv_texels.build(*d))
      return Status::error(ErrorCode::Unsupported, Check::None,
                           "cannot allocate the control variate's texel records");
    // The block form's sums: the finest grid of at most 16 x 16 blocks (a divisor of N) whose
    // sums over every view bin stay within max_block_sum_bytes; none when even 2 x 2 does not.
    PushforwardChannels block_layout = layout;
    block_layout.rank = std::min(d->options.block_sum_rank, layout.rank);
    const double bins = double(d->parallax.dirs()) * double(d->parallax.dirs());
    for (uint32_t blocks = 16; blocks >= 2; blocks /= 2) {
      const double bytes =
          double(blocks + 1) * (blocks + 1) * block_layout.count() * sizeof(float) * bins;
      if (d->n % blocks != 0 || !(bytes <= d->options.max_block_sum_bytes)) continue;
      if (!d->subperiod.init(d.get(), uint32_t(bins), block_layout, blocks))
        return Status::error(ErrorCode::Unsupported, Check::None,
                             "cannot allocate the block sums' bookkeeping");
      break;
    }
    // g_V's attenuation first: the visibility pilot then measures the g_V the estimates will use.
    if (d->options.attenuation_pilot) run_attenuation_pilot(d.get());
    if (d->options.visibility_samples > 0 && d->options.visibility_pilot)
      run_visibility_pilot(d.get());
  }
  data_ = std::move(d);
  return {};
}

namespace {

double square(double v) {
  return v * v;
}

Status check_arguments(const EvalData* data, const Footprint& footprint, LobeMask lobes,
                       const Estimate* out) {
  if (data == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "evaluator is not open");
  if (out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "estimate: null output");
  if (lobes == 0 || (lobes & ~kAllLobes) != 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "lobe mask 0x%x is empty or has unknown bits", unsigned(lobes));
  reader::FootprintPlan plan;
  if (reader::make_footprint_plan(footprint, data->n, &plan)) return {};
  return reader::plan_footprint(footprint, data->n, &plan);
}

void sum_value(Estimate* out) {
  out->value = Rgb();
  for (const Rgb& lobe : out->lobes)
    out->value += lobe;
}

}  // namespace

Status Evaluator::estimate(const Footprint& footprint, const double wi[3], const double wo[3],
                           Method method, uint32_t spp, Rng& rng, LobeMask lobes,
                           Estimate* out) const noexcept {
  Status s = check_arguments(data_.get(), footprint, lobes, out);
  if (!s.ok()) return s;
  if (spp == 0 && method != Method::Reference)
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "spp must be at least 1 for method %s", method_name(method));
  if (unsigned(method) >= unsigned(kMethodCount))
    return Status::error(ErrorCode::InvalidArgument, Check::None, "unknown method");
#ifdef CLOTHBAKE_SINGLE_FILE
  if (method == Method::MultiscalePaper)
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "method multiscale-paper is not in the single-file build");
#endif
  const bool multiscale = method == Method::Multiscale || method == Method::MultiscalePaper;
  if (multiscale && !data_->specular.present())
    return Status::error(
        ErrorCode::NotFound, Check::MissingSection,
        "method %s needs Integral-Radiance tables; this asset has none%s", method_name(method),
        data_->options.tables == TableChoice::Auto ? "" : " of the kind asked for");
  ShadingFrame frame;
  if (!make_frame(*data_, wi, wo, lobes, &frame, &s)) return s;
  *out = Estimate{};

  const double w = footprint.x1 - footprint.x0, h = footprint.y1 - footprint.y0;
  const double direct_side = data_->options.direct_max_side;
  // A zero-area footprint is a point (below 1e-12 texel^2 a footprint is its corner point for
  // every method: its area weights would lose their digits; a 1e-150 square gave 0, a 5e-324 one
  // NaN; docs/hardening.md): the exact value over the four view bins, except in brute force, which
  // samples it like any footprint (one view bin drawn per estimate: one BSDF evaluation per
  // sample, what a path tracer pays per ray).
  const bool point = !(w * h >= 1e-12);
  const bool direct =
      (point && method != Method::Brute) || (multiscale && w < direct_side && h < direct_side);
  // The unbiased form needs the compressed tables' images, and a footprint of at least
  // min_control_variate_side texels a side: smaller ones are sampled exactly as brute force (the
  // same random numbers: the view bin, then the points).
  if (method == Method::Multiscale && !direct && !data_->specular.is_compressed())
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "method multiscale needs compressed Integral-Radiance tables (the raw "
                         "ones have no images to integrate under the parallax); use "
                         "multiscale-paper, brute or reference with raw tables");
  // Too small a footprint for the control variate to pay is brute force's without further ado;
  // otherwise its cover, once per estimate, decides the branch and the estimator uses it.
  const bool unbiased_multiscale = method == Method::Multiscale && !direct;
  const bool without_cv =
      unbiased_multiscale && w * h < square(data_->options.min_control_variate_side);
  const FootprintCover cover =
      unbiased_multiscale && !without_cv ? cover_footprint(*data_, footprint) : FootprintCover{};
  if (multiscale && !direct && !without_cv) {  // a scene-planned asset answers only the half
                                               // vectors it kept
    const double hv[3] = {frame.h.x, frame.h.y, frame.h.z};
    if (!data_->specular.tables->covers_bins(hv))
      return Status::error(ErrorCode::OutOfPlan, Check::None,
                           "the half vector (%g, %g, %g) falls in a bin that this scene-planned "
                           "asset left out (bin_map instance 0)",
                           hv[0], hv[1], hv[2]);
  }
  const Footprint sampled =
      point ? Footprint{footprint.x0, footprint.y0, footprint.x0, footprint.y0} : footprint;
  if (direct) {
    out->counters.direct = true;
    s = exact_average(*data_, frame, sampled, 0, out);
  } else if (method == Method::Reference) {
    s = exact_average(*data_, frame, footprint, 0, out);
  } else if (method == Method::Brute || without_cv) {
    out->counters.without_control_variate = without_cv;
    brute_force(*data_, frame, sampled, spp, rng, out);
#ifndef CLOTHBAKE_SINGLE_FILE
  } else if (method == Method::MultiscalePaper) {
    s = paper_control_variates(*data_, frame, footprint, spp, rng, out);
#endif
  } else {
    s = pushforward_control_variates(*data_, frame, footprint, cover, spp, rng, out);
  }
  if (!s.ok()) return s;
  sum_value(out);
  // Values that validation accepts (finite, each within its section's range) can still overflow
  // in the control variate's sums (a visibility coefficient near the float maximum, found by the
  // C interface's fuzzer): such an estimate is refused, never returned.
  if (!std::isfinite(out->value.r) || !std::isfinite(out->value.g) ||
      !std::isfinite(out->value.b)) {
    *out = Estimate{};
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "the estimate is not finite: the asset's values overflow the evaluator's "
                         "sums");
  }
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE  // the C++ interface's extras, which the C interface does not offer
Status Evaluator::texel_value(int64_t x, int64_t y, const double wi[3], const double wo[3],
                              double visibility, LobeMask lobes, Rgb* out) const noexcept {
  if (data_ == nullptr || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "evaluator is not open");
  if (lobes == 0 || (lobes & ~kAllLobes) != 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "lobe mask is empty or unknown");
  if (!(visibility >= 0.0 && visibility <= 1.0))
    return Status::error(ErrorCode::InvalidArgument, Check::None, "visibility must be in [0, 1]");
  ShadingFrame frame;
  Status s;
  if (!make_frame(*data_, wi, wo, lobes, &frame, &s)) return s;
  Rgb lobes_value[model::kLobeCount];
  integrand_lobes(frame,
                  model::ClothBsdf<double>(data_->texel_params(data_->texel(x, y)))
                      .eval(frame.wi, frame.wo, visibility),
                  lobes_value);
  Rgb value;
  for (const Rgb& l : lobes_value)
    value += l;
  *out = value;
  return {};
}

Status Evaluator::reference_supersampled(const Footprint& footprint, const double wi[3],
                                         const double wo[3], uint32_t supersampling, LobeMask lobes,
                                         Estimate* out) const noexcept {
  Status s = check_arguments(data_.get(), footprint, lobes, out);
  if (!s.ok()) return s;
  if (supersampling == 0)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "supersampling must be >= 1");
  ShadingFrame frame;
  if (!make_frame(*data_, wi, wo, lobes, &frame, &s)) return s;
  *out = Estimate{};
  s = exact_average(*data_, frame, footprint, supersampling, out);
  if (!s.ok()) return s;
  sum_value(out);
  return {};
}
#endif

}  // namespace clothbake::eval

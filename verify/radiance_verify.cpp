// Verification of raw Integral-Radiance tables against the fabric (radiance_verify.hpp).
#include "verify/radiance_verify.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "common/error.hpp"
#include "formats/reader/cluster_sections.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/open_asset.hpp"
#include "model/sggx.hpp"
#include "tables/half_vector_bins.hpp"
#include "tables/radiance_fill.hpp"
#include "verify/footprint_sampling.hpp"

namespace clothbake::verify {
namespace {

using reader::RadianceTableKind;

[[noreturn]] void asset_error(const std::string& what, const reader::Status& status) {
  throw Error(ExitCode::InvalidAsset, what + ": " + formats::describe(status));
}

// Relative error against a reference, with the level floor (radiance_verify.hpp).
double relative_error(double value, double reference, double floor) {
  const double scale = std::max(std::abs(reference), floor);
  if (scale > 0) return std::abs(value - reference) / scale;
  return value == 0 ? 0.0 : INFINITY;
}

struct Accumulator {
  int footprints = 0, values = 0;
  double max = 0, sum_sq = 0, max_pure = 0;
  void add(double e, double pure) {
    ++values;
    max = std::max(max, e);
    sum_sq += e * e;
    if (pure >= 0) max_pure = std::max(max_pure, pure);
  }
};

std::vector<ErrorStats> finish(const std::vector<SizeClass>& classes,
                               const std::vector<Accumulator>& acc) {
  std::vector<ErrorStats> out;
  for (std::size_t k = 0; k < classes.size(); ++k) {
    if (acc[k].footprints == 0) continue;
    ErrorStats s;
    s.size_class = classes[k].name;
    s.footprints = acc[k].footprints;
    s.values = acc[k].values;
    s.max = acc[k].max;
    s.rms = acc[k].values ? std::sqrt(acc[k].sum_sq / acc[k].values) : 0.0;
    s.max_pure = acc[k].max_pure;
    out.push_back(s);
  }
  return out;
}

// Per-footprint results, filled in parallel and reduced in footprint order.
struct FootprintResult {
  std::vector<double> sat_error, sat_pure;  // per cluster (pure < 0: reference below the level)
  std::vector<double> dir_error, dir_pure;
  std::vector<char> counted;  // cluster has any texel value
};

KindReport verify_kind(const reader::Asset& asset, RadianceTableKind kind,
                       const tables::RadianceInputs& inputs, const RadianceVerifyOptions& options,
                       uint64_t seed) {
  reader::RawRadianceTables tables;
  if (const reader::Status s = tables.open(asset, kind); !s.ok())
    asset_error(std::string("cannot read the ") + reader::radiance_kind_name(kind) + " tables", s);
  const int n = inputs.resolution;
  if (int(tables.resolution()) != n || int(tables.cluster_count()) != inputs.cluster_count)
    throw Error(ExitCode::InvalidAsset, std::string("the ") + reader::radiance_kind_name(kind) +
                                            " tables do not match the label map (resolution " +
                                            std::to_string(tables.resolution()) + ", " +
                                            std::to_string(tables.cluster_count()) + " clusters)");
  const auto& info = tables.info();
  KindReport report;
  report.kind = reader::radiance_kind_name(kind);
  report.resolution = n;
  report.bins_per_side = int(info.bins_per_side);
  report.clusters = int(info.cluster_count);
  report.stored_clusters = int(info.stored_clusters);
  report.samples_per_bin_side = int(info.samples_per_bin_side);
  report.element_bits = int(info.element_bits);
  report.min_roughness = info.min_roughness;
  report.bins_needed = kind == RadianceTableKind::Specular
                           ? tables::bins_per_side_for_roughness(info.min_roughness)
                           : 1;
  const bool specular = kind == RadianceTableKind::Specular;
  const tables::HalfVectorBins bins =
      specular ? tables::make_half_vector_bins(int(info.bins_per_side),
                                               std::max(1, int(info.samples_per_bin_side)))
               : tables::HalfVectorBins{};

  const auto classes = size_classes(n);
  const auto footprints = sample_footprints(n, options.samples, seed);
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  const int clusters = inputs.cluster_count;
  std::vector<model::FibreSggx<double>> sggx;
  if (specular)
    for (std::size_t t = 0; t < texels; ++t) {
      const Vec3f& tg = inputs.tangent[t];
      sggx.push_back(model::FibreSggx<double>::make(model::Vec3d(tg[0], tg[1], tg[2]),
                                                    inputs.roughness[inputs.yarn_id[t]]));
    }

  // Batches of footprints whose bins' values fit a memory budget.
  const std::size_t budget_bins = std::max<std::size_t>(8, (std::size_t(512) << 20) / (texels * 4));
  std::vector<FootprintResult> results(footprints.size());
  std::vector<reader::BinWeights> weights(footprints.size());
  for (std::size_t i = 0; i < footprints.size(); ++i)
    if (!reader::make_bin_weights(info.bins_per_side, footprints[i].h, &weights[i]))
      throw_internal_error("verify: bad sampled half vector");
  std::size_t begin = 0;
  while (begin < footprints.size()) {
    std::set<uint32_t> needed;
    std::size_t end = begin;
    while (end < footprints.size()) {
      std::set<uint32_t> more = needed;
      for (uint32_t k = 0; k < weights[end].count; ++k)
        more.insert(weights[end].bin[k]);
      if (more.size() > budget_bins && end > begin) break;
      needed = std::move(more);
      ++end;
    }
    // Per-texel values and per-cluster tile means of every needed bin.
    std::vector<uint32_t> bin_list(needed.begin(), needed.end());
    std::map<uint32_t, std::size_t> slot;
    for (std::size_t k = 0; k < bin_list.size(); ++k)
      slot[bin_list[k]] = k;
    std::vector<std::vector<float>> values(bin_list.size(), std::vector<float>(texels));
    std::vector<std::vector<double>> mean(bin_list.size(), std::vector<double>(clusters, 0.0));
    tbb::parallel_for(std::size_t(0), bin_list.size(), [&](std::size_t k) {
      tables::radiance_bin_values(kind, inputs, bins, int(bin_list[k]), values[k].data());
      for (std::size_t t = 0; t < texels; ++t)
        mean[k][inputs.labels[t]] += double(values[k][t]) / double(texels);
    });
    tbb::parallel_for(begin, end, [&](std::size_t i) {
      const SampledFootprint& f = footprints[i];
      const reader::BinWeights& bw = weights[i];
      std::vector<double> answer(std::size_t(clusters), 0.0);
      if (!tables.try_query_all(f.rect, f.h, answer.data()))
        throw_internal_error("verify: a sampled footprint was rejected by the query");
      const auto wx = axis_coverage(f.rect.x0, f.rect.x1, n);
      const auto wy = axis_coverage(f.rect.y0, f.rect.y1, n);
      std::vector<double> direct(std::size_t(clusters), 0.0), level(std::size_t(clusters), 0.0);
      std::vector<double> exact(std::size_t(clusters), 0.0),
          exact_level(std::size_t(clusters), 0.0);
      for (uint32_t k = 0; k < bw.count; ++k) {
        const std::size_t s = slot.at(bw.bin[k]);
        for (int c = 0; c < clusters; ++c)
          level[std::size_t(c)] += bw.weight[k] * mean[s][std::size_t(c)];
        for (int y = 0; y < n; ++y) {
          if (wy[std::size_t(y)] == 0) continue;
          for (int x = 0; x < n; ++x) {
            if (wx[std::size_t(x)] == 0) continue;
            const std::size_t t = std::size_t(y) * std::size_t(n) + std::size_t(x);
            direct[inputs.labels[t]] +=
                bw.weight[k] * wx[std::size_t(x)] * wy[std::size_t(y)] * double(values[s][t]);
          }
        }
      }
      if (specular) {
        const model::Vec3d h(f.h[0], f.h[1], f.h[2]);
        for (std::size_t t = 0; t < texels; ++t) {
          const double d = double(inputs.gap[t]) * sggx[t].D(h);
          exact_level[inputs.labels[t]] += d / double(texels);
          const double cover = wx[t % std::size_t(n)] * wy[t / std::size_t(n)];
          if (cover != 0) exact[inputs.labels[t]] += cover * d;
        }
      }
      const double area = (f.rect.x1 - f.rect.x0) * (f.rect.y1 - f.rect.y0);
      FootprintResult& r = results[i];
      r.sat_error.resize(std::size_t(clusters));
      r.sat_pure.resize(std::size_t(clusters));
      r.dir_error.resize(std::size_t(clusters));
      r.dir_pure.resize(std::size_t(clusters));
      r.counted.resize(std::size_t(clusters));
      for (std::size_t c = 0; c < std::size_t(clusters); ++c) {
        r.counted[c] = level[c] > 0 || direct[c] > 0 || answer[c] != 0;
        const double floor = area * level[c];
        r.sat_error[c] = relative_error(answer[c], direct[c], floor);
        r.sat_pure[c] =
            direct[c] >= floor && direct[c] > 0 ? std::abs(answer[c] - direct[c]) / direct[c] : -1;
        if (specular) {
          const double efloor = area * exact_level[c];
          r.dir_error[c] = relative_error(answer[c], exact[c], efloor);
          r.dir_pure[c] =
              exact[c] >= efloor && exact[c] > 0 ? std::abs(answer[c] - exact[c]) / exact[c] : -1;
        }
      }
    });
    begin = end;
  }

  // Ordered reduction per size class.
  std::vector<Accumulator> sat(classes.size()), dir(classes.size());
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    const std::size_t k = std::size_t(footprints[i].size_class);
    const FootprintResult& r = results[i];
    ++sat[k].footprints;
    if (specular) ++dir[k].footprints;
    for (std::size_t c = 0; c < r.counted.size(); ++c) {
      if (!r.counted[c]) continue;
      if (r.sat_error[c] > report.sat_max || report.worst_sat.empty()) {
        std::ostringstream w;
        const auto& f = footprints[i];
        w << "cluster " << c << ", footprint [" << f.rect.x0 << ", " << f.rect.x1 << ") x ["
          << f.rect.y0 << ", " << f.rect.y1 << "), h (" << f.h[0] << ", " << f.h[1] << ", "
          << f.h[2] << ")";
        report.worst_sat = w.str();
      }
      report.sat_max = std::max(report.sat_max, r.sat_error[c]);
      sat[k].add(r.sat_error[c], r.sat_pure[c]);
      if (specular) {
        report.directional_max = std::max(report.directional_max, r.dir_error[c]);
        dir[k].add(r.dir_error[c], r.dir_pure[c]);
      }
    }
  }
  report.sat = finish(classes, sat);
  if (specular) report.directional = finish(classes, dir);
  return report;
}

}  // namespace

RadianceVerifyReport verify_radiance(const reader::Asset& asset, const Fabric& fabric,
                                     const RadianceVerifyOptions& options) {
  if (options.samples < 1) throw_input_error("verify: --samples must be at least 1");
  if (!(options.max_rel_error > 0)) throw_input_error("verify: --max-rel-error must be positive");
  if (options.max_dir_error && !(*options.max_dir_error > 0))
    throw_input_error("verify: --max-dir-error must be positive");
  reader::VisibilityClusterView view;
  if (const reader::Status s = view.open(asset); !s.ok())
    asset_error("cannot read the visibility clusters", s);
  const int n = int(view.resolution());
  if (fabric.maps.resolution != n)
    throw_input_error("verify: the fabric's maps are " + std::to_string(fabric.maps.resolution) +
                      "^2 but the asset's label map is " + std::to_string(n) +
                      "^2: was the asset baked from this fabric (and [bake] resolution)?");
  std::vector<uint8_t> labels(std::size_t(n) * std::size_t(n));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      labels[std::size_t(y) * std::size_t(n) + std::size_t(x)] = uint8_t(view.label(x, y));
  auto inputs = tables::radiance_inputs(fabric, labels, int(view.cluster_count()));
  tables::validate_radiance_inputs(inputs.view);

  RadianceVerifyReport report;
  report.max_rel_error = options.max_rel_error;
  report.max_dir_error = options.max_dir_error;
  const bool has_gaps =
      std::any_of(fabric.maps.gap.begin(), fabric.maps.gap.end(), [](float g) { return g < 1.0f; });
  for (RadianceTableKind kind : {RadianceTableKind::Specular, RadianceTableKind::Gap}) {
    reader::SectionInfo probe;
    const bool present =
        asset
            .find(reader::SectionType::RadianceRawTables,
                  reader::radiance_instance(kind, reader::RadiancePart::Info), &probe)
            .ok();
    const bool needed = kind == RadianceTableKind::Specular || has_gaps;
    if (!present) {
      if (needed)
        throw Error(ExitCode::InvalidAsset,
                    std::string("the asset has no raw ") + reader::radiance_kind_name(kind) +
                        " Integral-Radiance tables, which this fabric needs");
      continue;
    }
    KindReport k = verify_kind(asset, kind, inputs.view, options, options.seed + uint64_t(kind));
    if (!needed)
      report.failures.push_back(std::string("the asset has ") + k.kind +
                                " tables but the fabric has no gaps: not baked from this fabric?");
    if (k.sat_max > options.max_rel_error) {
      std::ostringstream m;
      m << k.kind << " tables: SAT error " << k.sat_max << " exceeds --max-rel-error "
        << options.max_rel_error << " (" << k.worst_sat << ")";
      report.failures.push_back(m.str());
    }
    if (options.max_dir_error && !k.directional.empty() &&
        k.directional_max > *options.max_dir_error) {
      std::ostringstream m;
      m << k.kind << " tables: directional error " << k.directional_max
        << " exceeds --max-dir-error " << *options.max_dir_error;
      if (k.bins_needed > k.bins_per_side)
        m << " (roughness " << k.min_roughness << " needs radiance_dirs >= " << k.bins_needed
          << ")";
      report.failures.push_back(m.str());
    }
    report.kinds.push_back(std::move(k));
  }
  report.passed = report.failures.empty();
  return report;
}

nlohmann::json report_json(const RadianceVerifyReport& report) {
  auto stats = [](const std::vector<ErrorStats>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& s : v)
      a.push_back({{"size_class", s.size_class},
                   {"footprints", s.footprints},
                   {"values", s.values},
                   {"max", s.max},
                   {"rms", s.rms},
                   {"max_pure_relative", s.max_pure}});
    return a;
  };
  nlohmann::json kinds = nlohmann::json::array();
  for (const auto& k : report.kinds)
    kinds.push_back({{"kind", k.kind},
                     {"resolution", k.resolution},
                     {"bins_per_side", k.bins_per_side},
                     {"clusters", k.clusters},
                     {"stored_clusters", k.stored_clusters},
                     {"samples_per_bin_side", k.samples_per_bin_side},
                     {"element_bits", k.element_bits},
                     {"min_roughness", k.min_roughness},
                     {"bins_needed_for_min_roughness", k.bins_needed},
                     {"sat_error", stats(k.sat)},
                     {"sat_error_max", k.sat_max},
                     {"worst_sat_error", k.worst_sat},
                     {"directional_error", stats(k.directional)},
                     {"directional_error_max", k.directional_max}});
  nlohmann::json thresholds = {{"max_rel_error", report.max_rel_error}};
  thresholds["max_dir_error"] =
      report.max_dir_error ? nlohmann::json(*report.max_dir_error) : nlohmann::json(nullptr);
  return {{"passed", report.passed},
          {"thresholds", thresholds},
          {"failures", report.failures},
          {"tables", kinds}};
}

std::string report_text(const RadianceVerifyReport& report) {
  std::ostringstream out;
  out.precision(3);
  for (const auto& k : report.kinds) {
    out << k.kind << " tables: " << k.resolution << "^2 texels, " << k.bins_per_side << "^2 bins ("
        << k.samples_per_bin_side << "^2 samples each), " << k.stored_clusters << "/" << k.clusters
        << " clusters stored, u" << k.element_bits << "\n";
    out << "  relative error by footprint size (side in texels):\n";
    out << "    size     footprints   SAT max    SAT rms    dir max    dir rms\n";
    for (std::size_t i = 0; i < k.sat.size(); ++i) {
      const auto& s = k.sat[i];
      out << "    " << std::left;
      out.width(9);
      out << s.size_class;
      out.width(13);
      out << s.footprints;
      out.width(11);
      out << s.max;
      out.width(11);
      out << s.rms;
      if (i < k.directional.size()) {
        out.width(11);
        out << k.directional[i].max;
        out << k.directional[i].rms;
      } else {
        out << "-          -";
      }
      out << "\n";
    }
    out << "  SAT vs direct sum: max " << k.sat_max << " (threshold " << report.max_rel_error
        << ")\n";
    if (!k.directional.empty()) {
      out << "  binned vs exact D(h): max " << k.directional_max;
      if (report.max_dir_error) out << " (threshold " << *report.max_dir_error << ")";
      if (k.bins_needed > k.bins_per_side)
        out << "; roughness " << k.min_roughness << " needs radiance_dirs >= " << k.bins_needed
            << " (2-sigma rule)";
      out << "\n";
    }
  }
  out << (report.passed ? "raw tables: passed" : "raw tables: FAILED") << "\n";
  for (const auto& f : report.failures)
    out << "  " << f << "\n";
  return out.str();
}

}  // namespace clothbake::verify

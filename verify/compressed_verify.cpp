// Compressed-against-raw verification (compressed_verify.hpp).
#include "verify/compressed_verify.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <optional>
#include <span>
#include <sstream>

#include "common/error.hpp"
#include "compress/directional_texels.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/splitmix64.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"
#include "verify/footprint_sampling.hpp"
#include "verify/report_text.hpp"

namespace clothbake::verify {
namespace {

using reader::RadianceTableKind;

[[noreturn]] void invalid_asset(const std::string& message) {
  throw Error(ExitCode::InvalidAsset, message);
}

double thread_seconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::string psnr_text(double db) {
  return db >= kExactPsnrDb ? "exact" : fixed_text(db, 1) + " dB";
}

// Per (cluster, bin) table: RMSE, max error, PSNR from the full decompression.
TableErrorSummary table_errors(const reader::CompressedRadianceTables& tables,
                               const compress::DirectionalTexels& raw) {
  const std::size_t n = std::size_t(raw.resolution), bins = std::size_t(raw.bins());
  const std::size_t clusters = std::size_t(raw.cluster_count), cells = clusters * bins;
  const std::size_t row_blocks = (n + 15) / 16;
  struct Acc {
    std::vector<double> err2, ref2, max_err, peak;
  };
  std::vector<Acc> partial(row_blocks);
  tbb::parallel_for(std::size_t(0), row_blocks, [&](std::size_t block) {
    Acc a{std::vector<double>(cells, 0.0), std::vector<double>(cells, 0.0),
          std::vector<double>(cells, 0.0), std::vector<double>(cells, 0.0)};
    std::vector<float> decoded(bins);
    for (std::size_t y = block * 16; y < std::min(n, block * 16 + 16); ++y)
      for (std::size_t x = 0; x < n; ++x) {
        const std::size_t t = y * n + x;
        const int c_decoded = tables.decode_texel(uint32_t(x), uint32_t(y), decoded.data());
        const uint8_t c_raw = raw.cluster[t];
        // A texel without a raw cluster is zero in every table; one the compressed tables give no
        // cell is zero there. Errors go to the raw texel's cluster (or the decoded one).
        const int c = c_raw != compress::kNoStratum ? int(c_raw) : c_decoded;
        if (c < 0) continue;
        for (std::size_t b = 0; b < bins; ++b) {
          const double ref = c_raw != compress::kNoStratum ? double(raw.row(t)[b]) : 0.0;
          const double got = c_decoded == c ? double(decoded[b]) : 0.0;
          const std::size_t i = std::size_t(c) * bins + b;
          const double d = got - ref;
          a.err2[i] += d * d;
          a.ref2[i] += ref * ref;
          a.max_err[i] = std::max(a.max_err[i], std::fabs(d));
          a.peak[i] = std::max(a.peak[i], ref);
        }
      }
    partial[block] = std::move(a);
  });
  std::vector<double> err2(cells, 0.0), ref2(cells, 0.0), max_err(cells, 0.0), peak(cells, 0.0);
  for (const auto& a : partial)
    for (std::size_t i = 0; i < cells; ++i) {
      err2[i] += a.err2[i];
      ref2[i] += a.ref2[i];
      max_err[i] = std::max(max_err[i], a.max_err[i]);
      peak[i] = std::max(peak[i], a.peak[i]);
    }
  TableErrorSummary s;
  std::vector<double> psnr;
  double total_err2 = 0.0, total_ref2 = 0.0;
  const double texels = double(n * n);
  for (std::size_t i = 0; i < cells; ++i) {
    total_err2 += err2[i];
    total_ref2 += ref2[i];
    s.max_abs_error = std::max(s.max_abs_error, max_err[i]);
    if (!(peak[i] > 0.0)) continue;
    ++s.tables;
    const double rmse = std::sqrt(err2[i] / texels);
    if (rmse / peak[i] > s.worst_relative_rmse || s.worst_table.empty()) {
      s.worst_relative_rmse = rmse / peak[i];
      s.worst_table = "cluster " + std::to_string(i / bins) + " bin " + std::to_string(i % bins);
    }
    psnr.push_back(rmse > 0.0 ? 20.0 * std::log10(peak[i] / rmse) : kExactPsnrDb);
  }
  if (!psnr.empty()) {
    std::sort(psnr.begin(), psnr.end());
    s.min_psnr_db = psnr.front();
    s.median_psnr_db = psnr[psnr.size() / 2];
  }
  s.texel_rms_relative = total_ref2 > 0.0 ? std::sqrt(total_err2 / total_ref2) : 0.0;
  return s;
}

// Footprint errors per size class.
void footprint_errors(const reader::CompressedRadianceTables& tables,
                      const compress::DirectionalTexels& raw,
                      const CompressedVerifyOptions& options, CompressedKindReport* report) {
  const int n = raw.resolution;
  const std::size_t bins = std::size_t(raw.bins()), clusters = std::size_t(raw.cluster_count);
  // Per-cluster mean texel value per bin (the level guarding the relative error).
  std::vector<double> level(clusters * bins, 0.0);
  for (std::size_t t = 0; t < raw.texels(); ++t)
    if (raw.cluster[t] != compress::kNoStratum)
      for (std::size_t b = 0; b < bins; ++b)
        level[std::size_t(raw.cluster[t]) * bins + b] += double(raw.row(t)[b]);
  for (double& l : level)
    l /= double(raw.texels());

  const auto classes = size_classes(n);
  const auto footprints = sample_footprints(n, options.samples, options.seed);
  struct Acc {
    double e2 = 0, r2 = 0, e2s = 0, r2s = 0, max_rel = 0;
    int count = 0;
  };
  std::vector<Acc> acc(classes.size());
  std::vector<double> got(clusters), want(clusters);
  for (const auto& fp : footprints) {
    reader::BinWeights bw;
    if (!reader::make_bin_weights(uint32_t(raw.bins_per_side), fp.h, &bw))
      throw_internal_error("verify: bad sampled half vector");
    if (!tables.try_query_all(fp.rect, fp.h, got.data()))
      throw_internal_error("verify: a sampled footprint was refused");
    const auto cx = axis_coverage(fp.rect.x0, fp.rect.x1, n);
    const auto cy = axis_coverage(fp.rect.y0, fp.rect.y1, n);
    std::fill(want.begin(), want.end(), 0.0);
    for (int y = 0; y < n; ++y) {
      if (cy[std::size_t(y)] == 0.0) continue;
      for (int x = 0; x < n; ++x) {
        if (cx[std::size_t(x)] == 0.0) continue;
        const std::size_t t = std::size_t(y) * std::size_t(n) + std::size_t(x);
        if (raw.cluster[t] == compress::kNoStratum) continue;
        double v = 0.0;
        for (uint32_t w = 0; w < bw.count; ++w)
          v += bw.weight[w] * double(raw.row(t)[bw.bin[w]]);
        want[raw.cluster[t]] += cx[std::size_t(x)] * cy[std::size_t(y)] * v;
      }
    }
    const double area = (fp.rect.x1 - fp.rect.x0) * (fp.rect.y1 - fp.rect.y0);
    Acc& a = acc[std::size_t(fp.size_class)];
    ++a.count;
    double gs = 0, ws = 0;
    for (std::size_t c = 0; c < clusters; ++c) {
      const double d = got[c] - want[c];
      a.e2 += d * d;
      a.r2 += want[c] * want[c];
      gs += got[c];
      ws += want[c];
      double lvl = 0.0;
      for (uint32_t w = 0; w < bw.count; ++w)
        lvl += bw.weight[w] * level[c * bins + bw.bin[w]];
      const double guard = std::max(std::fabs(want[c]), area * lvl);
      if (guard > 0.0) a.max_rel = std::max(a.max_rel, std::fabs(d) / guard);
    }
    a.e2s += (gs - ws) * (gs - ws);
    a.r2s += ws * ws;
  }
  for (std::size_t k = 0; k < classes.size(); ++k) {
    FootprintClassError e;
    e.size_class = classes[k].name;
    e.min_side = classes[k].min_side;
    e.footprints = acc[k].count;
    e.rms_relative = acc[k].r2 > 0 ? std::sqrt(acc[k].e2 / acc[k].r2) : 0.0;
    e.rms_relative_sum = acc[k].r2s > 0 ? std::sqrt(acc[k].e2s / acc[k].r2s) : 0.0;
    e.max_relative = acc[k].max_rel;
    report->classes.push_back(e);
  }
  // Smallest side from which every class meets the threshold.
  report->min_reliable_side = std::numeric_limits<double>::infinity();
  for (std::size_t k = report->classes.size(); k-- > 0;) {
    if (report->classes[k].footprints > 0 &&
        report->classes[k].rms_relative > options.max_footprint_error)
      break;
    report->min_reliable_side = report->classes[k].min_side;
  }
}

// Queries per second on one thread (thread CPU time), best of 3 passes.
double queries_per_second(const reader::RadianceTables& tables,
                          const std::vector<reader::Footprint>& rects,
                          const std::vector<std::array<double, 3>>& hs) {
  std::vector<double> out(tables.cluster_count());
  double best = 1e300, sink = 0.0;
  for (int pass = 0; pass < 3; ++pass) {
    const double t0 = thread_seconds();
    for (std::size_t i = 0; i < rects.size(); ++i) {
      tables.try_query_all(rects[i], hs[i].data(), out.data());
      sink += out[0];
    }
    best = std::min(best, thread_seconds() - t0);
  }
  if (!std::isfinite(sink)) throw_internal_error("verify: non-finite query results");
  return best > 0.0 ? double(rects.size()) / best : 0.0;
}

void throughput(const reader::Asset& asset, const reader::CompressedRadianceTables& tables,
                const tables::RadianceInputs& inputs, const compress::DirectionalTexels& raw,
                const CompressedVerifyOptions& options, CompressedKindReport* report) {
  // Pixel-like footprints: 1 to 16 texels per side, anywhere, random half vectors.
  model::SplitMix64 rng(options.seed ^ 0x5eedull);
  const double n = raw.resolution;
  std::vector<reader::Footprint> rects(static_cast<std::size_t>(options.throughput_queries));
  std::vector<std::array<double, 3>> hs(rects.size());
  for (std::size_t i = 0; i < rects.size(); ++i) {
    const double x0 = rng.uniform() * n, y0 = rng.uniform() * n, side = 1.0 + 15.0 * rng.uniform();
    rects[i] = {x0, y0, x0 + side, y0 + side};
    const double ct = rng.uniform(), phi = 2.0 * M_PI * rng.uniform(), st = std::sqrt(1 - ct * ct);
    hs[i] = {st * std::cos(phi), st * std::sin(phi), std::max(ct, 1e-3)};
  }
  reader::RawRadianceTables raw_tables;
  std::vector<std::byte> bytes;
  reader::Asset built;
  const RadianceTableKind kind = raw.kind;
  if (raw_tables.open(asset, kind).ok()) {
    report->raw_from_asset = true;
  } else {
    tables::RadianceOptions o;
    o.bins_per_side = raw.bins_per_side;
    o.samples_per_side = raw.samples_per_bin_side;
    o.warn_unresolved = false;
    tables::RadianceTableSet set = kind == RadianceTableKind::Specular
                                       ? tables::build_specular_tables(inputs, o)
                                       : tables::build_gap_tables(inputs, o);
    {
      std::vector<formats::Section> sections = tables::radiance_sections(std::move(set));
      bytes = formats::serialize_asset(sections);
    }
    const reader::Status s = built.open_memory(bytes.data(), bytes.size());
    if (!s.ok())
      throw_internal_error(std::string("verify: raw tables built in memory: ") + s.message());
    const reader::Status t = raw_tables.open(built, kind);
    if (!t.ok())
      throw_internal_error(std::string("verify: raw tables built in memory: ") + t.message());
  }
  report->raw_queries_per_second = queries_per_second(raw_tables, rects, hs);
  report->compressed_queries_per_second = queries_per_second(tables, rects, hs);
  report->cost_ratio = report->compressed_queries_per_second > 0
                           ? report->raw_queries_per_second / report->compressed_queries_per_second
                           : 0.0;
  report->throughput_measured = true;
}

// The raw tables the asset keeps, as exact texel values recovered from its fixed-point SATs (what
// the compress stage started from), or nothing when the asset does not keep them. Malformed raw
// tables are an invalid asset.
std::optional<compress::DirectionalTexels> raw_texels_from_asset(const reader::Asset& asset,
                                                                 RadianceTableKind kind,
                                                                 std::span<const uint8_t> labels) {
  reader::RawRadianceTables checked;  // validates the four sections' shapes against each other
  const reader::Status s = checked.open(asset, kind);
  if (s.code() == reader::ErrorCode::NotFound) return std::nullopt;
  if (!s.ok())
    invalid_asset(std::string("verify: the asset's raw ") + reader::radiance_kind_name(kind) +
                  " tables: " + s.message());
  reader::SectionInfo parts[4];
  for (uint32_t p = 0; p < 4; ++p)
    if (!asset
             .find(reader::SectionType::RadianceRawTables,
                   reader::radiance_instance(kind, reader::RadiancePart(p)), &parts[p])
             .ok())
      return std::nullopt;
  const unsigned char* base = asset.bytes();
  tables::RadianceSectionView view;
  view.info = reinterpret_cast<const reader::RadianceTableInfoRecord*>(base + parts[0].offset);
  view.clusters = {reinterpret_cast<const uint32_t*>(base + parts[1].offset),
                   std::size_t(parts[1].stored_size / 4)};
  view.units = {reinterpret_cast<const double*>(base + parts[2].offset),
                std::size_t(parts[2].stored_size / 8)};
  view.sat = reinterpret_cast<const std::byte*>(base + parts[3].offset);
  // Both the raw tables and the label map come from the asset: a disagreement between them is an
  // invalid asset (exit 3), not the input error directional_texels reports for its callers.
  try {
    return compress::directional_texels(view, labels);
  } catch (const Error& e) {
    if (e.code() != ExitCode::Input) throw;
    invalid_asset(std::string("verify: the asset's raw ") + reader::radiance_kind_name(kind) +
                  " tables disagree with its label map: " + e.what());
  }
}

}  // namespace

namespace {
bool has_info_section(const reader::Asset& asset, reader::SectionType type, bool compressed) {
  for (uint32_t k = 0; k < reader::kRadianceKindCount; ++k) {
    const auto kind = RadianceTableKind(k);
    const uint32_t instance = compressed
                                  ? reader::compressed_instance(kind, reader::CompressedPart::Info)
                                  : reader::radiance_instance(kind, reader::RadiancePart::Info);
    reader::SectionInfo info;
    if (asset.find(type, instance, &info).ok()) return true;
  }
  return false;
}
}  // namespace

bool has_compressed_tables(const reader::Asset& asset) {
  return has_info_section(asset, reader::SectionType::RadianceCompressedTables, true);
}

bool has_raw_tables(const reader::Asset& asset) {
  return has_info_section(asset, reader::SectionType::RadianceRawTables, false);
}

CompressedVerifyReport verify_compressed(const reader::Asset& asset, const Fabric& fabric,
                                         const CompressedVerifyOptions& options) {
  CompressedVerifyReport report;
  report.options = options;
  reader::ArrayView<uint8_t> label_view;
  const reader::Status ls = asset.array(reader::SectionType::ClusterLabels, 0, &label_view);
  if (!ls.ok())
    invalid_asset(std::string("verify: the asset has no cluster label map: ") + ls.message());
  const std::vector<uint8_t> labels(label_view.begin(), label_view.end());

  for (uint32_t k = 0; k < reader::kRadianceKindCount; ++k) {
    const auto kind = RadianceTableKind(k);
    reader::CompressedRadianceTables tables;
    const reader::Status s = tables.open(asset, kind);
    if (s.code() == reader::ErrorCode::NotFound) continue;
    if (!s.ok()) invalid_asset(std::string("verify: ") + s.check_id() + " " + s.message());
    const auto& info = tables.info();
    const int n = int(info.resolution);
    if (fabric.maps.resolution != n)
      throw_input_error("verify: the fabric's maps are " + std::to_string(fabric.maps.resolution) +
                        "^2 texels, the asset's compressed tables " + std::to_string(n) + "^2");
    if (labels.size() != std::size_t(n) * std::size_t(n))
      invalid_asset("verify: the label map does not have " + std::to_string(n) + "^2 texels");
    for (uint8_t l : labels)
      if (l >= info.cluster_count)
        invalid_asset("verify: a label is not below the cluster count " +
                      std::to_string(info.cluster_count));

    CompressedKindReport r;
    r.kind = reader::radiance_kind_name(kind);
    r.resolution = n;
    r.bins_per_side = int(info.bins_per_side);
    r.clusters = int(info.cluster_count);
    r.cells = int(info.cell_count);
    r.images = int(info.image_count);
    r.bake_error = info.bake_error;
    r.decoded_bytes = tables.decoded_bytes();
    // Ranks and stored bytes from the sections.
    r.min_rank = 1 << 30;
    for (uint32_t p = 0; p < reader::kCompressedPartCount; ++p) {
      reader::SectionInfo si;
      if (asset
              .find(reader::SectionType::RadianceCompressedTables,
                    reader::compressed_instance(kind, reader::CompressedPart(p)), &si)
              .ok())
        r.compressed_bytes += si.stored_size;
    }
    const auto inputs = tables::radiance_inputs(fabric, labels, int(info.cluster_count));
    // The reference: the asset's own raw tables when it keeps them, else recomputed from the
    // fabric with the asset's label map and the quadrature its info record states.
    std::optional<compress::DirectionalTexels> kept = raw_texels_from_asset(asset, kind, labels);
    r.raw_reference_from_asset = kept.has_value();
    const compress::DirectionalTexels raw =
        kept ? std::move(*kept)
             : compress::directional_texels(kind, inputs.view, int(info.bins_per_side),
                                            int(info.samples_per_bin_side));
    kept.reset();
    if (raw.resolution != n || raw.bins_per_side != int(info.bins_per_side))
      invalid_asset("verify: the asset's raw " + r.kind +
                    " tables do not match its compressed ones (resolution or bins)");
    {
      std::vector<char> used(256, 0);
      for (uint8_t c : raw.cluster)
        if (c != compress::kNoStratum) used[c] = 1;
      uint64_t stored = 0;
      for (char u : used)
        stored += uint64_t(u);
      r.raw_float_bytes = stored * uint64_t(raw.bins()) * raw.texels() * 4;
    }
    r.ratio = r.compressed_bytes ? double(r.raw_float_bytes) / double(r.compressed_bytes) : 0.0;
    {
      reader::ArrayView<uint32_t> cells;
      reader::SectionInfo si;
      if (asset
              .find(reader::SectionType::RadianceCompressedTables,
                    reader::compressed_instance(kind, reader::CompressedPart::Cells), &si)
              .ok() &&
          asset.view_of(si, &cells).ok())
        for (uint32_t g = 0; g < info.cell_count; ++g) {
          r.min_rank = std::min(r.min_rank, int(cells[g * reader::kCellFields + 1]));
          r.max_rank = std::max(r.max_rank, int(cells[g * reader::kCellFields + 1]));
        }
      if (info.cell_count == 0) r.min_rank = 0;
    }
    r.tables = table_errors(tables, raw);
    footprint_errors(tables, raw, options, &r);
    if (options.throughput) throughput(asset, tables, inputs.view, raw, options, &r);

    for (const auto& c : r.classes)
      if (c.min_side >= options.threshold_side && c.footprints > 0 &&
          c.rms_relative > options.max_footprint_error)
        report.failures.push_back(
            r.kind + ": footprints of class " + c.size_class + " have an RMS relative error of " +
            fixed_text(c.rms_relative, 5) + " > " + general_text(options.max_footprint_error));
    if (options.min_ratio && r.ratio < *options.min_ratio)
      report.failures.push_back(r.kind + ": compression ratio " + fixed_text(r.ratio, 1) + " < " +
                                fixed_text(*options.min_ratio, 1));
    if (options.max_texel_error && r.tables.texel_rms_relative > *options.max_texel_error)
      report.failures.push_back(r.kind + ": relative RMS texel error " +
                                fixed_text(r.tables.texel_rms_relative, 5) + " > " +
                                general_text(*options.max_texel_error));
    report.kinds.push_back(std::move(r));
  }
  if (report.kinds.empty())
    invalid_asset("verify: the asset has no compressed Integral-Radiance tables");
  report.passed = report.failures.empty();
  return report;
}

nlohmann::json compressed_report_json(const CompressedVerifyReport& report) {
  nlohmann::json kinds = nlohmann::json::array();
  auto finite_or_null = [](double v) -> nlohmann::json {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  for (const auto& r : report.kinds) {
    nlohmann::json classes = nlohmann::json::array();
    for (const auto& c : r.classes)
      classes.push_back({{"class", c.size_class},
                         {"min_side", c.min_side},
                         {"footprints", c.footprints},
                         {"rms_relative", c.rms_relative},
                         {"rms_relative_cluster_sum", c.rms_relative_sum},
                         {"max_relative", c.max_relative}});
    nlohmann::json k = {
        {"kind", r.kind},
        {"resolution", r.resolution},
        {"bins_per_side", r.bins_per_side},
        {"clusters", r.clusters},
        {"cells", r.cells},
        {"images", r.images},
        {"min_rank", r.min_rank},
        {"max_rank", r.max_rank},
        {"compressed_bytes", r.compressed_bytes},
        {"raw_float_bytes", r.raw_float_bytes},
        {"decoded_bytes", r.decoded_bytes},
        {"ratio", r.ratio},
        {"bake_error", r.bake_error},
        {"raw_reference", r.raw_reference_from_asset ? "asset" : "fabric"},
        {"tables",
         {{"count", r.tables.tables},
          {"texel_rms_relative", r.tables.texel_rms_relative},
          {"worst_relative_rmse", r.tables.worst_relative_rmse},
          {"worst_table", r.tables.worst_table},
          {"min_psnr_db", r.tables.min_psnr_db},
          {"median_psnr_db", r.tables.median_psnr_db},
          {"max_abs_error", r.tables.max_abs_error}}},
        {"footprints", classes},
        {"min_reliable_side", finite_or_null(r.min_reliable_side)},
    };
    if (r.throughput_measured)
      k["throughput"] = {{"compressed_queries_per_second", r.compressed_queries_per_second},
                         {"raw_queries_per_second", r.raw_queries_per_second},
                         {"cost_ratio", r.cost_ratio},
                         {"raw_from_asset", r.raw_from_asset},
                         {"clock", "thread CPU time, one thread"}};
    kinds.push_back(k);
  }
  nlohmann::json thresholds = {{"max_footprint_error", report.options.max_footprint_error},
                               {"threshold_side", report.options.threshold_side}};
  if (report.options.min_ratio) thresholds["min_ratio"] = *report.options.min_ratio;
  if (report.options.max_texel_error)
    thresholds["max_texel_error"] = *report.options.max_texel_error;
  return {{"compressed", kinds},
          {"thresholds", thresholds},
          {"passed", report.passed},
          {"failures", report.failures}};
}

std::string compressed_report_text(const CompressedVerifyReport& report) {
  std::ostringstream o;
  for (const auto& r : report.kinds) {
    o << "compressed " << r.kind << " tables: " << r.resolution << "^2 texels, " << r.bins_per_side
      << "^2 bins, " << r.clusters << " clusters -> " << r.cells << " C-PCA cells, ranks "
      << r.min_rank << ".." << r.max_rank << ", " << r.images << " images; against raw tables "
      << (r.raw_reference_from_asset ? "kept in the asset" : "recomputed from the fabric") << "\n";
    o << "  size: " << r.compressed_bytes << " bytes against " << r.raw_float_bytes
      << " of raw float tables (" << fixed_text(r.ratio, 1) << ":1); decoded in memory "
      << fixed_text(double(r.decoded_bytes) / 1048576.0, 1) << " MiB\n";
    o << "  texels: relative RMS error " << fixed_text(100 * r.tables.texel_rms_relative, 3)
      << " % (bake claimed " << fixed_text(100 * r.bake_error, 3) << " %), " << r.tables.tables
      << " tables, PSNR min " << psnr_text(r.tables.min_psnr_db) << " / median "
      << psnr_text(r.tables.median_psnr_db) << ", worst RMSE/peak "
      << fixed_text(r.tables.worst_relative_rmse, 5) << " (" << r.tables.worst_table
      << "), max abs error " << general_text(r.tables.max_abs_error) << "\n";
    o << "  footprints (RMS relative per cluster / of the cluster sum / max guarded):\n";
    for (const auto& c : r.classes)
      o << "    " << c.size_class
        << (c.size_class.size() < 5 ? std::string(5 - c.size_class.size(), ' ') : "") << " "
        << fixed_text(100 * c.rms_relative, 3) << " % / " << fixed_text(100 * c.rms_relative_sum, 3)
        << " % / " << fixed_text(100 * c.max_relative, 2) << " %  (" << c.footprints << ")\n";
    if (std::isfinite(r.min_reliable_side))
      o << "  use the compressed tables for footprints of side >= "
        << fixed_text(r.min_reliable_side, 0) << " texels; below, evaluate the texels directly\n";
    else
      o << "  no footprint size meets the threshold: do not use these compressed tables\n";
    if (r.throughput_measured)
      o << "  queries (one thread, CPU time): compressed "
        << fixed_text(r.compressed_queries_per_second / 1e6, 2) << " M/s, raw "
        << fixed_text(r.raw_queries_per_second / 1e6, 2) << " M/s"
        << (r.raw_from_asset ? "" : " (raw built in memory)") << ": compressed costs "
        << fixed_text(r.cost_ratio, 2) << "x raw\n";
  }
  o << (report.passed ? "compressed tables: passed\n" : "compressed tables: FAILED\n");
  for (const auto& f : report.failures)
    o << "  " << f << "\n";
  return o.str();
}

}  // namespace clothbake::verify

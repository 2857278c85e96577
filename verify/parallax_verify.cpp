// Compressed-against-raw parallax verification (parallax_verify.hpp).
#include "verify/parallax_verify.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "common/error.hpp"
#include "compress/parallax_codes.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/writer/asset_writer.hpp"
#include "raycast/parallax.hpp"
#include "raycast/raycast_sections.hpp"
#include "verify/footprint_sampling.hpp"
#include "verify/report_text.hpp"

namespace clothbake::verify {
namespace {

constexpr double kQuarterTexel = 0.25;

// Stored bytes of every section of the given type.
uint64_t stored_bytes(const reader::Asset& asset, reader::SectionType type) {
  uint64_t bytes = 0;
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    reader::SectionInfo info;
    if (asset.section(i, &info).ok() && info.type == type) bytes += info.stored_size;
  }
  return bytes;
}

}  // namespace

bool has_compressed_parallax(const reader::Asset& asset) {
  for (uint32_t i = 0; i < 6; ++i) {
    reader::SectionInfo info;
    if (asset.find(reader::SectionType::ParallaxEntropy, i, &info).ok()) return true;
  }
  return false;
}

ParallaxVerifyReport verify_parallax(const reader::Asset& asset, const Fabric& fabric,
                                     const ParallaxVerifyOptions& options) {
  ParallaxVerifyReport report;
  report.options = options;
  reader::ParallaxView packed;
  if (const reader::Status s = packed.open(asset, reader::ParallaxSource::Compressed); !s.ok())
    throw Error(ExitCode::InvalidAsset,
                std::string("verify: compressed parallax: ") + s.check_id() + " " + s.message());
  const int n = int(packed.resolution()), dirs = int(packed.dirs());
  report.resolution = n;
  report.dirs = dirs;
  report.min_cos = packed.info().min_cos;
  report.bits = int(packed.compressed_info().bits);
  report.section = "parallax_entropy";

  // The raw reference: the asset's own, else recomputed (the bake's ray casting) and held in an
  // in-memory asset so that the same reader answers both.
  reader::ParallaxView raw;
  std::vector<std::byte> bytes;
  reader::Asset built;
  if (raw.open(asset, reader::ParallaxSource::Raw).ok() && raw.has_sat()) {
    report.raw_reference_from_asset = true;
  } else {
    if (fabric.maps.resolution != n)
      throw_input_error("verify: the fabric's resolution " +
                        std::to_string(fabric.maps.resolution) +
                        " differs from the asset's parallax table (" + std::to_string(n) +
                        "): not the fabric the asset was baked from");
    raycast::ParallaxSettings settings;
    settings.dirs = dirs;
    settings.min_cos = packed.info().min_cos;
    raycast::ParallaxTable table = raycast::bake_parallax(fabric.maps, settings);
    {
      std::vector<formats::Section> sections = raycast::parallax_sections(std::move(table));
      bytes = formats::serialize_asset(sections);
    }
    const reader::Status s = built.open_memory(bytes.data(), bytes.size());
    if (!s.ok())
      throw_internal_error(std::string("verify: parallax built in memory: ") + s.message());
    const reader::Status t = raw.open(built, reader::ParallaxSource::Raw);
    if (!t.ok())
      throw_internal_error(std::string("verify: parallax built in memory: ") + t.message());
  }
  if (int(raw.resolution()) != n || int(raw.dirs()) != dirs ||
      raw.info().min_cos != packed.info().min_cos)
    throw Error(ExitCode::InvalidAsset,
                "verify: the asset's raw and compressed parallax tables differ in resolution, "
                "directions or cap");

  // Per texel and bin centre, one partial sum per direction (summed in order: deterministic).
  const std::vector<double> k = compress::parallax_offset_per_depth(n, dirs, report.min_cos);
  const std::size_t d_count = std::size_t(dirs) * std::size_t(dirs);
  struct Acc {
    double err2 = 0, max = 0, depth = 0;
    uint64_t above = 0;
  };
  std::vector<Acc> acc(d_count);
  tbb::parallel_for(std::size_t(0), d_count, [&](std::size_t d) {
    Acc a;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double dr =
            std::abs(packed.bin_depth(uint32_t(d), x, y) - raw.bin_depth(uint32_t(d), x, y));
        const double e = dr * k[d];
        a.err2 += e * e;
        a.max = std::max(a.max, e);
        a.depth = std::max(a.depth, dr);
        a.above += e > kQuarterTexel ? 1 : 0;
      }
    acc[d] = a;
  });
  double err2 = 0;
  uint64_t above = 0;
  for (const Acc& a : acc) {
    err2 += a.err2;
    above += a.above;
    report.max_error = std::max(report.max_error, a.max);
    report.max_depth_error = std::max(report.max_depth_error, a.depth);
  }
  report.entries = uint64_t(d_count) * uint64_t(n) * uint64_t(n);
  report.rms_error = std::sqrt(err2 / double(report.entries));
  report.share_above_quarter = double(above) / double(report.entries);

  // Footprints.
  const auto classes = size_classes(n);
  const auto footprints = sample_footprints(n, options.samples, options.seed);
  std::vector<double> fp_err(footprints.size(), 0.0);
  tbb::parallel_for(std::size_t(0), footprints.size(), [&](std::size_t i) {
    reader::ParallaxSample a, b;
    const reader::Status sa = packed.footprint_depth(footprints[i].rect, footprints[i].h, &a);
    const reader::Status sb = raw.footprint_depth(footprints[i].rect, footprints[i].h, &b);
    if (!sa.ok() || !sb.ok()) {
      fp_err[i] = -1.0;
      return;
    }
    fp_err[i] = double(n) * std::hypot(a.offset[0] - b.offset[0], a.offset[1] - b.offset[1]);
  });
  report.classes.resize(classes.size());
  std::vector<double> class_err2(classes.size(), 0.0);
  for (std::size_t c = 0; c < classes.size(); ++c) {
    report.classes[c].size_class = classes[c].name;
    report.classes[c].min_side = classes[c].min_side;
  }
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    if (fp_err[i] < 0.0)
      throw_internal_error("verify: a parallax footprint query failed (SAT allocation)");
    ParallaxClassError& c = report.classes[std::size_t(footprints[i].size_class)];
    ++c.footprints;
    class_err2[std::size_t(footprints[i].size_class)] += fp_err[i] * fp_err[i];
    c.max_error = std::max(c.max_error, fp_err[i]);
  }
  for (std::size_t c = 0; c < classes.size(); ++c)
    if (report.classes[c].footprints > 0)
      report.classes[c].rms_error = std::sqrt(class_err2[c] / double(report.classes[c].footprints));

  // Sizes.
  report.compressed_bytes = stored_bytes(asset, reader::SectionType::ParallaxEntropy);
  report.raw_bytes = 64 + report.entries * 6;
  report.ratio =
      report.compressed_bytes > 0 ? double(report.raw_bytes) / double(report.compressed_bytes) : 0;

  // Thresholds.
  auto fail = [&](const std::string& f) {
    report.passed = false;
    report.failures.push_back("parallax: " + f);
  };
  if (report.rms_error > options.max_rms_error)
    fail("per-texel RMS offset error " + general_text(report.rms_error) + " texel above " +
         general_text(options.max_rms_error));
  if (options.max_error && report.max_error > *options.max_error)
    fail("per-texel maximum offset error " + general_text(report.max_error) + " texel above " +
         general_text(*options.max_error));
  if (options.max_share_above && report.share_above_quarter > *options.max_share_above)
    fail("share of entries above 0.25 texel " + general_text(report.share_above_quarter) +
         " above " + general_text(*options.max_share_above));
  for (const ParallaxClassError& c : report.classes)
    if (c.footprints > 0 && c.min_side >= options.footprint_min_side &&
        c.rms_error > options.max_footprint_error)
      fail("footprint class " + c.size_class + ": RMS offset error " + general_text(c.rms_error) +
           " texel above " + general_text(options.max_footprint_error));
  if (options.min_ratio && report.ratio < *options.min_ratio)
    fail("size ratio " + general_text(report.ratio) + " below " + general_text(*options.min_ratio));
  return report;
}

nlohmann::json parallax_report_json(const ParallaxVerifyReport& r) {
  nlohmann::json classes = nlohmann::json::array();
  for (const ParallaxClassError& c : r.classes)
    if (c.footprints > 0)
      classes.push_back({{"size_class", c.size_class},
                         {"min_side", c.min_side},
                         {"footprints", c.footprints},
                         {"rms_offset_error_texels", c.rms_error},
                         {"max_offset_error_texels", c.max_error}});
  nlohmann::json thresholds = {{"max_rms_error", r.options.max_rms_error},
                               {"max_footprint_error", r.options.max_footprint_error},
                               {"footprint_min_side", r.options.footprint_min_side}};
  if (r.options.max_error) thresholds["max_error"] = *r.options.max_error;
  if (r.options.max_share_above) thresholds["max_share_above"] = *r.options.max_share_above;
  if (r.options.min_ratio) thresholds["min_ratio"] = *r.options.min_ratio;
  return {{"verified", true},
          {"resolution", r.resolution},
          {"dirs", r.dirs},
          {"min_cos", r.min_cos},
          {"bits", r.bits},
          {"section", r.section},
          {"raw_reference", r.raw_reference_from_asset ? "asset" : "recomputed from the fabric"},
          {"entries", r.entries},
          {"texel",
           {{"rms_offset_error_texels", r.rms_error},
            {"max_offset_error_texels", r.max_error},
            {"share_above_quarter_texel", r.share_above_quarter},
            {"max_depth_error", r.max_depth_error}}},
          {"footprints", classes},
          {"compressed_bytes", r.compressed_bytes},
          {"raw_bytes", r.raw_bytes},
          {"ratio", r.ratio},
          {"thresholds", thresholds},
          {"samples", r.options.samples},
          {"passed", r.passed},
          {"failures", r.failures}};
}

std::string parallax_report_text(const ParallaxVerifyReport& r) {
  std::ostringstream s;
  s << "parallax (compressed, " << r.section << ", " << r.bits << "-bit codes, " << r.resolution
    << "^2 x " << r.dirs << "^2 directions) against the raw table "
    << (r.raw_reference_from_asset ? "in the asset" : "recomputed from the fabric") << ":\n";
  s << "  per texel (" << r.entries << " entries): RMS offset error " << fixed_text(r.rms_error, 4)
    << " texel, max " << fixed_text(r.max_error, 4) << ", above 0.25 texel "
    << fixed_text(100.0 * r.share_above_quarter, 3) << " %\n";
  s << "  footprint class   footprints   RMS (texel)   max (texel)\n";
  for (const ParallaxClassError& c : r.classes)
    if (c.footprints > 0) {
      std::string name = c.size_class;
      name.resize(std::max<std::size_t>(name.size(), 16), ' ');
      s << "  " << name << "  " << c.footprints << "   " << fixed_text(c.rms_error, 4) << "   "
        << fixed_text(c.max_error, 4) << "\n";
    }
  s << "  size: " << r.compressed_bytes << " bytes against " << r.raw_bytes << " raw ("
    << fixed_text(r.ratio, 1) << ":1)\n";
  s << "  parallax " << (r.passed ? "passed" : "FAILED") << "\n";
  return s.str();
}

}  // namespace clothbake::verify

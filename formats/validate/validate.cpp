// Deep validation (validate.hpp).
#include "formats/validate/validate.hpp"

#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "formats/reader/cluster_sections.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/map_entropy.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#ifndef CLOTHBAKE_SINGLE_FILE  // the single file's shading reads no raw tables: it skips them
#include "formats/reader_raw/radiance_tables.hpp"
#endif
#include "formats/validate/checksums.hpp"
#ifndef CLOTHBAKE_SINGLE_FILE  // shading reads no metadata: the single file leaves its check out
#include "formats/validate/metadata_limits.hpp"
#endif
#include "model/parameter_ranges.hpp"

namespace clothbake::reader {
namespace {

class Reporter {
 public:
  Reporter(FindingCallback callback, void* user) : callback_(callback), user_(user) {}

  void report(Check check, uint32_t section, const char* format, ...)
#if defined(__GNUC__)
      __attribute__((format(printf, 4, 5)))
#endif
  {
    char message[Status::kMessageCapacity];
    va_list args;
    va_start(args, format);
    std::vsnprintf(message, sizeof message, format, args);
    va_end(args);
    if (is_warning(check))
      ++summary_.warnings;
    else
      ++summary_.errors;
    if (callback_) callback_(user_, check, section, message);
  }
  void report_status(const Status& status, uint32_t section) {
    report(status.check() == Check::None ? Check::SectionLayout : status.check(), section, "%s",
           status.message());
  }
  ValidationSummary summary() const {
    return summary_;
  }

 private:
  FindingCallback callback_;
  void* user_;
  ValidationSummary summary_;
};

const char* describe(char* buf, std::size_t cap, const SectionInfo& s) {
  return describe_section(buf, cap, s.index, uint32_t(s.type), s.instance);
}

bool all_zero(const unsigned char* p, uint64_t n, uint64_t* first_nonzero) {
  for (uint64_t i = 0; i < n; ++i)
    if (p[i] != 0) {
      *first_nonzero = i;
      return false;
    }
  return true;
}

bool finite_value(const unsigned char* p, ElementType type) {
  switch (type) {
    case ElementType::F16: {
      uint16_t bits;
      std::memcpy(&bits, p, 2);
      return ((bits >> 10) & 0x1f) != 0x1f;
    }
    case ElementType::F32: {
      float v;
      std::memcpy(&v, p, 4);
      return std::isfinite(v);
    }
    case ElementType::F64: {
      double v;
      std::memcpy(&v, p, 8);
      return std::isfinite(v);
    }
    default:
      return true;
  }
}

// NaN/Inf in any floating-point section (the writer refuses them, so any is corruption or a
// foreign writer's bug).
void check_finite(const SectionInfo& s, Reporter& r) {
  if (s.codec != Codec::Raw) return;
  const uint32_t size = element_size(s.element_type);
  if (s.element_type != ElementType::F16 && s.element_type != ElementType::F32 &&
      s.element_type != ElementType::F64)
    return;
  const uint64_t count = s.raw_size / size;
  uint64_t bad = 0, first = 0;
  for (uint64_t i = 0; i < count; ++i)
    if (!finite_value(s.data + i * size, s.element_type)) {
      if (bad++ == 0) first = i;
    }
  if (bad) {
    char what[96];
    r.report(Check::NonFinite, s.index,
             "%s: %" PRIu64 " NaN or Inf values (first at element %" PRIu64 ")",
             describe(what, sizeof what, s), bad, first);
  }
}

#ifndef CLOTHBAKE_SINGLE_FILE
// Metadata: valid UTF-8 (no overlongs, surrogates or code points past U+10FFFF) and a JSON object
// at the top level (first and last non-blank characters are braces; full JSON parsing is the
// tool's job, `clothbake validate` does it).
void check_metadata(const Asset& asset, Reporter& r) {
  SectionInfo s;
  Status status = asset.find(SectionType::Metadata, 0, &s);
  if (!status.ok()) {
    r.report(Check::MissingSection, kNoSection, "no metadata section (required)");
    return;
  }
  std::string_view text;
  status = asset.metadata_json(&text);
  if (!status.ok()) {
    r.report_status(status, s.index);
    return;
  }
  const std::size_t n = text.size();
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos) {
    r.report(Check::Metadata, s.index, "metadata: NUL byte at offset %zu", nul);
    return;
  }
  if (const std::size_t bad = utf8_error_offset(text); bad != n) {
    r.report(Check::Metadata, s.index, "metadata: invalid UTF-8 at offset %zu", bad);
    return;
  }
  auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  std::size_t first = 0, last = n;
  while (first < n && blank(text[first]))
    ++first;
  while (last > first && blank(text[last - 1]))
    --last;
  if (last - first < 2 || text[first] != '{' || text[last - 1] != '}') {
    r.report(Check::Metadata, s.index, "metadata: not a JSON object");
    return;
  }
  status = check_metadata_limits(text);
  if (!status.ok()) r.report_status(status, s.index);
}
#endif

bool in_range(double v, double lo, double hi) {
  return v >= lo && v <= hi;
}

void check_fabric_records(const Asset& asset, Reporter& r, uint32_t* yarn_count,
                          int64_t* info_resolution) {
  SectionInfo s;
  const FabricInfoRecord* info = nullptr;
  if (asset.find(SectionType::FabricInfo, 0, &s).ok()) {
    Status status = read_fabric_info(asset, &info);
    if (!status.ok()) {
      r.report_status(status, s.index);
      info = nullptr;
    } else {
      uint64_t at;
      if (!all_zero(info->reserved, sizeof info->reserved, &at))
        r.report(Check::Padding, s.index, "fabric_info: reserved byte %" PRIu64 " is not zero",
                 uint64_t(offsetof(FabricInfoRecord, reserved)) + at);
      if (!model::roughness_in_range(info->sheen_roughness))
        r.report(Check::ValueRange, s.index, "fabric_info: sheen_roughness %g is outside [1e-4, 1]",
                 info->sheen_roughness);
      if (!(info->tile_size_mm >= 0) || !std::isfinite(info->tile_size_mm))
        r.report(Check::ValueRange, s.index, "fabric_info: tile_size_mm %g is not >= 0",
                 info->tile_size_mm);
      for (double c : info->sheen_color)
        if (!(c >= 0)) {
          r.report(Check::ValueRange, s.index, "fabric_info: sheen_color component %g < 0", c);
          break;
        }
      *info_resolution = info->resolution;
    }
  }
  ArrayView<YarnMaterialRecord> yarns;
  if (asset.find(SectionType::YarnMaterials, 0, &s).ok()) {
    Status status = read_yarn_materials(asset, &yarns);
    if (!status.ok()) {
      r.report_status(status, s.index);
      return;
    }
    *yarn_count = uint32_t(yarns.size);
    if (info && info->yarn_count != yarns.size)
      r.report(Check::SectionLayout, s.index,
               "yarn_materials: %" PRIu64 " records but fabric_info.yarn_count is %u",
               uint64_t(yarns.size), unsigned(info->yarn_count));
    for (uint64_t i = 0; i < yarns.size; ++i) {
      const YarnMaterialRecord& y = yarns[i];
      if (std::memchr(y.name, 0, sizeof y.name) == nullptr) {
        r.report(Check::SectionLayout, s.index,
                 "yarn_materials[%" PRIu64 "]: name is not NUL-terminated", i);
      } else {
#ifndef CLOTHBAKE_SINGLE_FILE  // names are text for reports, never shaded
        const std::string_view name(y.name, std::strlen(y.name));
        const std::size_t bad = utf8_error_offset(name);
        if (bad != name.size())
          r.report(Check::MetadataSchema, s.index,
                   "yarn_materials[%" PRIu64 "]: name is not UTF-8 (byte %zu)", i, bad);
#endif
      }
      uint64_t at;
      if (!all_zero(y.reserved, sizeof y.reserved, &at))
        r.report(Check::Padding, s.index,
                 "yarn_materials[%" PRIu64 "]: reserved byte %" PRIu64 " is not zero", i,
                 uint64_t(offsetof(YarnMaterialRecord, reserved)) + at);
      if (!model::roughness_in_range(y.roughness))
        r.report(Check::ValueRange, s.index,
                 "yarn_materials[%" PRIu64 "]: roughness %g is outside [1e-4, 1]", i, y.roughness);
      if (!(y.optical_thickness > 0) || !std::isfinite(y.optical_thickness))
        r.report(Check::ValueRange, s.index,
                 "yarn_materials[%" PRIu64 "]: optical_thickness %g is not > 0", i,
                 y.optical_thickness);
      const double* rgb[] = {y.specular_albedo, y.diffuse_reflectance, y.diffuse_transmittance,
                             y.color};
      const char* rgb_names[] = {"specular_albedo", "diffuse_reflectance", "diffuse_transmittance",
                                 "color"};
      for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c)
          if (!in_range(rgb[k][c], 0.0, 1.0)) {
            r.report(Check::ValueRange, s.index,
                     "yarn_materials[%" PRIu64 "]: %s component %d = %g is outside [0, 1]", i,
                     rgb_names[k], c, rgb[k][c]);
            break;
          }
    }
  } else if (info && info->yarn_count != 0) {
    r.report(Check::MissingSection, kNoSection,
             "fabric_info.yarn_count is %u but there is no yarn_materials section",
             unsigned(info->yarn_count));
  }
}

void check_feature_maps(const Asset& asset, Reporter& r, uint32_t yarn_count, bool have_yarns,
                        int64_t info_resolution) {
  const SectionType map_types[] = {SectionType::HeightMap, SectionType::TangentMap,
                                   SectionType::NormalMap, SectionType::GapMap,
                                   SectionType::YarnIdMap, SectionType::AlbedoMap};
  int present = 0;
  SectionInfo s;
  for (SectionType t : map_types)
    present += asset.find(t, 0, &s).ok() ? 1 : 0;
  if (present == 0) return;
  FeatureMaps maps;
  Status status = read_feature_maps(asset, &maps);
  if (!status.ok()) {
    r.report_status(status, kNoSection);
    return;
  }
  const uint32_t n = maps.resolution;
  const uint64_t texels = uint64_t(n) * n;
  if (info_resolution < 0)
    r.report(Check::MissingSection, kNoSection,
             "feature maps are present but there is no fabric_info section");
  else if (uint32_t(info_resolution) != n)
    r.report(Check::MapResolution, kNoSection,
             "feature maps are %u x %u but fabric_info.resolution is %u", unsigned(n), unsigned(n),
             unsigned(info_resolution));
  auto texel_xy = [n](uint64_t t, unsigned* x, unsigned* y) {
    *x = unsigned(t % n);
    *y = unsigned(t / n);
  };
  // Ranges of the scalar maps and the yarn ids.
  uint64_t bad = 0, first = 0;
  // The coded height hides its f16 codes from check_finite: check the decoded values.
  for (uint64_t t = 0; t < texels; ++t)
    if (!std::isfinite(maps.height[t]) && bad++ == 0) first = t;
  if (bad) {
    unsigned x, y;
    texel_xy(first, &x, &y);
    r.report(Check::NonFinite, kNoSection,
             "height map: %" PRIu64 " NaN or Inf texels (first at x=%u, y=%u)", bad, x, y);
  }
  bad = 0;
  for (uint64_t t = 0; t < texels; ++t)
    if (!(maps.gap[t] >= 0.f && maps.gap[t] <= 1.f) && bad++ == 0) first = t;
  if (bad) {
    unsigned x, y;
    texel_xy(first, &x, &y);
    r.report(Check::ValueRange, kNoSection,
             "gap map: %" PRIu64 " texels outside [0, 1] (first at x=%u, y=%u: %g)", bad, x, y,
             double(maps.gap[first]));
  }
  bad = 0;
  for (uint64_t t = 0; t < texels * 3; ++t)
    if (!(maps.albedo[t] >= 0.f && maps.albedo[t] <= 1.f) && bad++ == 0) first = t / 3;
  if (bad) {
    unsigned x, y;
    texel_xy(first, &x, &y);
    r.report(Check::ValueRange, kNoSection,
             "albedo map: %" PRIu64 " values outside [0, 1] (first at x=%u, y=%u)", bad, x, y);
  }
  if (have_yarns) {
    bad = 0;
    for (uint64_t t = 0; t < texels; ++t)
      if (maps.yarn_id[t] >= yarn_count && bad++ == 0) first = t;
    if (bad) {
      unsigned x, y;
      texel_xy(first, &x, &y);
      r.report(Check::YarnIdRange, kNoSection,
               "yarn_id map: %" PRIu64 " texels name a yarn >= %u (first at x=%u, y=%u: %u)", bad,
               unsigned(yarn_count), x, y, unsigned(maps.yarn_id[first]));
    }
  } else {
    r.report(Check::MissingSection, kNoSection,
             "feature maps are present but there is no yarn_materials section");
  }
  // Unit vectors (tolerance for float rounding and 8-bit sources), normal z > 0.
  struct Named {
    const char* name;
    const ArrayView<float>* map;
  } vectors[] = {{"tangent", &maps.tangent}, {"normal", &maps.normal}};
  for (const auto& v : vectors) {
    bad = 0;
    for (uint64_t t = 0; t < texels; ++t) {
      const float* p = v.map->data + 3 * t;
      const double len = std::sqrt(double(p[0]) * p[0] + double(p[1]) * p[1] + double(p[2]) * p[2]);
      if (!(std::fabs(len - 1.0) <= 1e-3) && bad++ == 0) first = t;
    }
    if (bad) {
      unsigned x, y;
      texel_xy(first, &x, &y);
      r.report(Check::NotUnitVector, kNoSection,
               "%s map: %" PRIu64 " texels are not unit vectors (first at x=%u, y=%u)", v.name, bad,
               x, y);
    }
  }
  bad = 0;
  for (uint64_t t = 0; t < texels; ++t)
    if (!(maps.normal[3 * t + 2] > 0.f) && bad++ == 0) first = t;
  if (bad) {
    unsigned x, y;
    texel_xy(first, &x, &y);
    r.report(Check::ValueRange, kNoSection,
             "normal map: %" PRIu64 " texels have z <= 0 (first at x=%u, y=%u)", bad, x, y);
  }
}

bool has_type(const Asset& asset, SectionType type, uint32_t first_instance = 0,
              uint32_t end_instance = 0xffffffffu) {
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    SectionInfo s;
    if (asset.section(i, &s).ok() && s.type == type && s.instance >= first_instance &&
        s.instance < end_instance)
      return true;
  }
  return false;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // the single file reads the compressed parallax only
// The parallax SAT must be the inclusive SAT (mod 2^32) of the depth codes: O(D N^2).
void check_parallax_sat(const Asset& asset, const ParallaxView& view, Reporter& r) {
  SectionInfo codes_info, sat_info;
  ArrayView<uint16_t> codes;
  ArrayView<uint32_t> sat;
  if (!asset.find(SectionType::ParallaxTable, 1, &codes_info).ok() ||
      !asset.find(SectionType::ParallaxSat, 0, &sat_info).ok() ||
      !asset.view_of(codes_info, &codes).ok() || !asset.view_of(sat_info, &sat).ok() ||
      codes.size != sat.size)
    return;  // open() accepted the shapes; nothing else to compare
  const uint64_t n = view.resolution(), dirs = uint64_t(view.dirs()) * view.dirs();
  if (codes.size != dirs * n * n) return;
  for (uint64_t d = 0; d < dirs; ++d)
    for (uint64_t y = 0; y < n; ++y)
      for (uint64_t x = 0; x < n; ++x) {
        const uint64_t t = (d * n + y) * n + x;
        const uint32_t expected = uint32_t(codes[t] + (x ? sat[t - 1] : 0u) +
                                           (y ? sat[t - n] : 0u) - (x && y ? sat[t - n - 1] : 0u));
        if (sat[t] != expected) {
          r.report(kCheckCrossSection, sat_info.index,
                   "parallax_sat: direction %" PRIu64 " texel (%" PRIu64 ", %" PRIu64
                   ") is %u, the SAT of the parallax codes gives %u",
                   d, x, y, unsigned(sat[t]), unsigned(expected));
          return;
        }
      }
}
#endif

// The compressed parallax: every stored block must decode exactly (CBK-E021); codes of an
// all-zero direction (step 0) must be 0; beside a raw table it must decode to it within its
// recorded depth error (CBK-E022). O(D N^2).
void check_compressed_parallax(const Asset& asset, const ParallaxView& packed, Reporter& r) {
  SectionInfo codes_info;
  const char* name = "parallax_entropy";
  if (!asset.find(SectionType::ParallaxEntropy, kEntropyParallaxStreamInstance, &codes_info).ok())
    return;
  {
    const Status s = packed.decode_all();
    if (!s.ok()) {
      r.report_status(s, codes_info.index);
      return;
    }
  }
  const uint64_t n = packed.resolution(), dirs = uint64_t(packed.dirs()) * packed.dirs();
  for (uint64_t d = 0; d < dirs; ++d)
    if (packed.covers(uint32_t(d)) && packed.depth_step(uint32_t(d)) == 0.0)
      for (uint64_t t = 0; t < n * n; ++t) {
        const unsigned c = packed.bin_code(uint32_t(d), int64_t(t % n), int64_t(t / n));
        if (c != 0) {
          r.report(Check::ValueRange, codes_info.index,
                   "%s: direction %" PRIu64 " has step 0 but texel (%" PRIu64 ", %" PRIu64
                   ") has code %u",
                   name, d, t % n, t / n, c);
          return;
        }
      }
#ifndef CLOTHBAKE_SINGLE_FILE
  ParallaxView raw;
  if (!raw.open(asset, ParallaxSource::Raw).ok() || raw.resolution() != n ||
      raw.dirs() != packed.dirs())
    return;
  const double tolerance = packed.compressed_info().max_depth_error * (1 + 1e-9) + 1e-15;
  for (uint64_t d = 0; d < dirs; ++d)
    for (uint64_t t = 0; t < n * n; ++t) {
      const double a = raw.bin_depth(uint32_t(d), int64_t(t % n), int64_t(t / n));
      const double b = packed.bin_depth(uint32_t(d), int64_t(t % n), int64_t(t / n));
      if (!(std::fabs(a - b) <= tolerance)) {
        r.report(kCheckCrossSection, codes_info.index,
                 "%s: direction %" PRIu64 " texel (%" PRIu64 ", %" PRIu64
                 ") decodes to %.9g, the raw table has %.9g (recorded max error %.3g)",
                 name, d, t % n, t / n, b, a, packed.compressed_info().max_depth_error);
        return;
      }
    }
#endif
}

// Opens the baked tables as a renderer does and checks them against each other and the maps:
// resolutions (CBK-E016), cluster counts and supports, raw against compressed (CBK-E022), and
// every view's own open() checks (their IDs).
void check_baked_tables(const Asset& asset, Reporter& r, int64_t reference_resolution) {
  int64_t resolution = reference_resolution;
  const char* resolution_from = "fabric_info";
  auto check_resolution = [&](const char* what, uint32_t n) {
    if (resolution < 0) {
      resolution = n;
      resolution_from = what;
    } else if (uint32_t(resolution) != n) {
      r.report(Check::MapResolution, kNoSection, "%s is %u x %u but %s is %u x %u", what,
               unsigned(n), unsigned(n), resolution_from, unsigned(resolution),
               unsigned(resolution));
    }
  };
#ifndef CLOTHBAKE_SINGLE_FILE
  if (has_type(asset, SectionType::ParallaxTable) || has_type(asset, SectionType::ParallaxSat)) {
    ParallaxView parallax;
    const Status s = parallax.open(asset, ParallaxSource::Raw);
    if (!s.ok()) {
      r.report_status(s, kNoSection);
    } else {
      check_resolution("parallax", parallax.resolution());
      if (parallax.has_sat()) check_parallax_sat(asset, parallax, r);
    }
  }
#endif
  if (has_type(asset, SectionType::ParallaxEntropy)) {
    ParallaxView packed;
    const Status s = packed.open(asset, ParallaxSource::Compressed);
    if (!s.ok()) {
      r.report_status(s, kNoSection);
    } else {
      check_resolution("parallax_entropy", packed.resolution());
      check_compressed_parallax(asset, packed, r);
    }
  }
  if (has_type(asset, SectionType::VisibilityAsg) || has_type(asset, SectionType::AsgFitError)) {
    VisibilityAsgView visibility;
    const Status s = visibility.open(asset);
    if (!s.ok())
      r.report_status(s, kNoSection);
    else
      check_resolution("visibility_asg", visibility.resolution());
  }
  VisibilityClusterView clusters;
  bool have_clusters = false;
  if (has_type(asset, SectionType::ClusterLabels) ||
      has_type(asset, SectionType::ClusterMeanVisibility)) {
    const Status s = clusters.open(asset);
    if (!s.ok()) {
      r.report_status(s, kNoSection);
    } else {
      have_clusters = true;
      check_resolution("cluster_labels", clusters.resolution());
    }
  }
  if (has_type(asset, SectionType::ClusterVisibilityBasis)) {
    VisibilityBasisView basis;
    const Status s = basis.open(asset);
    if (!s.ok()) {
      r.report_status(s, kNoSection);
    } else {
      if (basis.rank() > 0) check_resolution("cluster_visibility_basis", basis.resolution());
      if (have_clusters && basis.cluster_count() != clusters.cluster_count())
        r.report(Check::CrossSection, kNoSection,
                 "cluster_visibility_basis has %u clusters, the label map %u",
                 unsigned(basis.cluster_count()), unsigned(clusters.cluster_count()));
      else if (!have_clusters)
        r.report(Check::MissingSection, kNoSection,
                 "cluster_visibility_basis is present but there are no cluster sections");
    }
  }
  SectionInfo labels_info;
  ArrayView<uint8_t> labels;
  if (have_clusters && (!asset.find(SectionType::ClusterLabels, 0, &labels_info).ok() ||
                        !asset.view_of(labels_info, &labels).ok()))
    have_clusters = false;
  for (uint32_t k = 0; k < kRadianceKindCount; ++k) {
    const RadianceTableKind kind = RadianceTableKind(k);
    const char* name = radiance_kind_name(kind);
    const bool raw_present = has_type(asset, SectionType::RadianceRawTables, k * 16, k * 16 + 16);
    const bool packed_present =
        has_type(asset, SectionType::RadianceCompressedTables, k * 16, k * 16 + 16);
    if ((raw_present || packed_present) && !have_clusters &&
        !has_type(asset, SectionType::ClusterLabels))
      r.report(Check::MissingSection, kNoSection,
               "the %s Integral-Radiance tables are present but there is no cluster_labels "
               "section to say which texels belong to which cluster",
               name);
#ifndef CLOTHBAKE_SINGLE_FILE
    RawRadianceTables raw;
    bool raw_ok = false;
    if (raw_present) {
      Status s = raw.open(asset, kind);
      if (!s.ok()) {
        r.report_status(s, kNoSection);
      } else {
        raw_ok = true;
        check_resolution(k == 0 ? "radiance_tables (specular)" : "radiance_tables (gap)",
                         raw.resolution());
        s = raw.check_contents();
        if (!s.ok()) r.report_status(s, kNoSection);
        if (have_clusters && raw.cluster_count() != clusters.cluster_count()) {
          r.report(kCheckCrossSection, kNoSection,
                   "radiance_tables (%s) has %u clusters, the label map %u", name,
                   unsigned(raw.cluster_count()), unsigned(clusters.cluster_count()));
        } else if (have_clusters && s.ok() && raw.resolution() == clusters.resolution()) {
          s = raw.check_against_labels(labels.data);
          if (!s.ok()) r.report_status(s, kNoSection);
        }
      }
    }
#endif
    if (packed_present) {
      CompressedRadianceTables packed;
      const Status s = packed.open(asset, kind);
      if (!s.ok()) {
        r.report_status(s, kNoSection);
        continue;
      }
      check_resolution(k == 0 ? "radiance_compressed (specular)" : "radiance_compressed (gap)",
                       packed.resolution());
      if (have_clusters && packed.cluster_count() != clusters.cluster_count()) {
        r.report(kCheckCrossSection, kNoSection,
                 "radiance_compressed (%s) has %u clusters, the label map %u", name,
                 unsigned(packed.cluster_count()), unsigned(clusters.cluster_count()));
      } else if (have_clusters && packed.resolution() == clusters.resolution()) {
        const uint32_t n = packed.resolution();
        bool reported = false;
        for (uint32_t y = 0; y < n && !reported; ++y)
          for (uint32_t x = 0; x < n && !reported; ++x) {
            const int c = packed.cluster_of_texel(x, y);
            const uint32_t label = labels.data[uint64_t(y) * n + x];
            if (c >= 0 && uint32_t(c) != label) {
              r.report(kCheckCrossSection, kNoSection,
                       "radiance_compressed (%s): texel (%u, %u) is compressed in cluster %d "
                       "but the label map puts it in cluster %u",
                       name, unsigned(x), unsigned(y), c, unsigned(label));
              reported = true;
            }
          }
      }
#ifndef CLOTHBAKE_SINGLE_FILE
      if (raw_ok && (raw.resolution() != packed.resolution() ||
                     raw.bins_per_side() != packed.bins_per_side() ||
                     raw.cluster_count() != packed.cluster_count()))
        r.report(kCheckCrossSection, kNoSection,
                 "the raw and compressed %s tables differ in shape: %u^2 texels, %u^2 bins, %u "
                 "clusters against %u^2, %u^2, %u",
                 name, unsigned(raw.resolution()), unsigned(raw.bins_per_side()),
                 unsigned(raw.cluster_count()), unsigned(packed.resolution()),
                 unsigned(packed.bins_per_side()), unsigned(packed.cluster_count()));
#endif
    }
  }
}

}  // namespace

ValidationSummary validate_asset(const Asset& asset, FindingCallback callback,
                                 void* user) noexcept {
  Reporter r(callback, user);
  if (!asset.is_open()) {
    r.report(Check::None, kNoSection, "asset is not open");
    return r.summary();
  }
  const FileHeader& header = asset.header();
  const unsigned char* bytes = asset.bytes();
  const bool newer_minor = header.version_minor > kFormatMinor;
  if (const Status h = verify_header_checksum(asset); !h.ok()) r.report_status(h, kNoSection);
  if (newer_minor)
    r.report(Check::NewerMinor, kNoSection,
             "asset format %u.%u is newer than this reader (%u.%u): sections it does not know are "
             "skipped",
             unsigned(header.version_major), unsigned(header.version_minor), unsigned(kFormatMajor),
             unsigned(kFormatMinor));
  uint64_t at;
  if (!all_zero(header.reserved, sizeof header.reserved, &at))
    r.report(Check::Padding, kNoSection, "header: reserved byte %" PRIu64 " is not zero",
             uint64_t(offsetof(FileHeader, reserved)) + at);

  // Per section: checksum, padding after it, known type and version, finite floats.
  const uint64_t table_end =
      sizeof(FileHeader) + uint64_t(header.section_count) * header.section_entry_size;
  uint64_t cursor = table_end;  // end of the previous structure
  char what[96];
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    SectionInfo s;
    if (!asset.section(i, &s).ok()) continue;
    describe(what, sizeof what, s);
    if (!all_zero(bytes + cursor, s.offset - cursor, &at))
      r.report(Check::Padding, kNoSection,
               "padding byte at offset %" PRIu64 " (before %s) is not zero", cursor + at, what);
    cursor = s.offset + s.stored_size;
    Status status = verify_section(asset, s);
    if (!status.ok()) {
      r.report_status(status, i);
      continue;  // the content is not trustworthy: skip its semantic checks
    }
    if (section_type_name(s.type) == nullptr) {
      r.report(Check::UnknownSection, i, "%s: unknown type, skipped", what);
      continue;
    }
    if (s.codec != Codec::Raw) {
      r.report(Check::UnknownCodecNewer, i, "%s: codec %u unknown to this reader, skipped", what,
               unsigned(s.codec));
      continue;
    }
    const uint16_t known = known_section_version(s.type);
    if (known != 0 && (s.version == 0 || s.version > known)) {
      if (s.version > known && newer_minor)
        r.report(Check::NewerSectionVersion, i, "%s: payload version %u is newer than %u, skipped",
                 what, unsigned(s.version), unsigned(known));
      else
        r.report(Check::SectionLayout, i, "%s: payload version %u is not defined (this reader: %u)",
                 what, unsigned(s.version), unsigned(known));
      continue;
    }
    check_finite(s, r);
  }
  if (!all_zero(bytes + cursor, header.file_size - cursor, &at))
    r.report(Check::Padding, kNoSection,
             "padding byte at offset %" PRIu64 " (end of file) is not zero", cursor + at);
  // Stop before semantic checks if the bytes cannot be trusted.
  if (r.summary().errors > 0) return r.summary();

#ifndef CLOTHBAKE_SINGLE_FILE
  check_metadata(asset, r);
#endif
  uint32_t yarn_count = 0;
  int64_t info_resolution = -1;  // -1: no fabric_info
  check_fabric_records(asset, r, &yarn_count, &info_resolution);
  SectionInfo s;
  const bool have_yarns = asset.find(SectionType::YarnMaterials, 0, &s).ok();
  check_feature_maps(asset, r, yarn_count, have_yarns, info_resolution);
  check_baked_tables(asset, r, info_resolution);
  return r.summary();
}

}  // namespace clothbake::reader

// Up-front peak-memory estimate of a bake (memory_estimate.hpp). Every size below names the
// allocation it stands for; the constants per texel are the element sizes of the code (FabricMaps,
// model::AsgRecord, ...). Calibrated against measured peaks in docs/performance.md.
#include "bake/stages/memory_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/plan.hpp"
#include "bake/stages/stages.hpp"
#include "common/error.hpp"
#include "tables/fixed_point_sat.hpp"
#include "tables/half_vector_bins.hpp"
#include "tables/radiance_fill.hpp"

namespace clothbake::stages {
namespace {

// FabricMaps per texel: height f32, tangent, normal, albedo 3 x f32, gap f32, yarn id u16.
constexpr double kMapBytesPerTexel = 4 + 12 + 12 + 12 + 4 + 2;
// Decoded image pixels of an image fabric, all held until the maps are built: at most 1 + 3 + 3 +
// 1 + 1 + 3 float channels (bake/inputs/fabric_load.cpp keeps every MapImage).
constexpr double kImageBytesPerTexel = 12 * 4;
// The height field's Embree scene (raycast/heightfield_scene.cpp): (N+1)^2 vertices, 2 N^2
// triangles and their BVH, about 100 bytes a texel (measured: docs/performance.md). One scene is
// alive at a time (parallax, then visibility).
constexpr double kEmbreeBytesPerTexel = 100;
// Visibility per texel: AsgRecord (12 bytes) and fit error (f32), decoded lobes
// (model::AsgParams<float>, 28 bytes), and the two sections (records and errors).
constexpr double kAsgBytesPerTexel = 12 + 4;
constexpr double kLobeBytesPerTexel = 28;
// Cluster: the K-means features of every texel (float, ~8 per texel) and distances, the label map
// (artifact and section).
constexpr double kKmeansBytesPerTexel = 8 * 4 + 8;
constexpr double kLabelBytesPerTexel = 2;
// The streaming fills (bake/stages/table_streaming.hpp): copies of tangent, gap, yarn id and
// labels (19 bytes), per fill the texel's column (i16), the specular fill's SGGX SoA blocks (six
// floats).
constexpr double kStreamedInputBytesPerTexel = 12 + 4 + 2 + 1;
constexpr double kFillColumnBytesPerTexel = 2;
constexpr double kSggxBytesPerTexel = 6 * 4;
// directional_texels(fill): one 16-bin block of floats per thread.
constexpr double kBinBlock = 16;
// C-PCA oversampling (compress::CpcaOptions::oversampling) and SVD block rows.
constexpr double kOversampling = 8;
constexpr double kSvdBlockRows = 1024;
// The first rank cap of the C-PCA's target mode (compress/cpca.cpp).
constexpr double kTargetFirstRankCap = 16;

struct Builder {
  MemoryEstimate out;
  double resident = kBaseProcessBytes;
  const std::vector<std::string>& run;

  bool runs(const std::string& stage) const {
    return run.empty() || std::find(run.begin(), run.end(), stage) != run.end();
  }
  // A stage that adds `working` at its peak (outputs included) and leaves `kept` resident.
  void add(const std::string& stage, double working, double kept, std::string what,
           std::vector<std::string> keys) {
    if (!runs(stage)) return;
    StageMemory s;
    s.stage = stage;
    s.working_bytes = working;
    s.peak_bytes = resident + working;
    s.kept_bytes = kept;
    resident += kept;
    s.resident_bytes = resident;
    s.what = std::move(what);
    s.keys = std::move(keys);
    if (out.stages.empty() || s.peak_bytes > out.peak_bytes) {
      out.peak_bytes = s.peak_bytes;
      out.peak_stage = out.stages.size();
    }
    out.stages.push_back(std::move(s));
  }
};

// The C-PCA's working memory on one stratum of `rows` rows of dimension `dim` at SVD width
// `width` (compress/cpca.cpp, compress/randomized_svd.cpp): Y = A Omega and its Householder QR and
// Q (three rows x width doubles), or Q plus the per-block partials of A^T Q (ceil(rows / 1024)
// blocks of dim x width doubles) and Z; the Gaussian test matrix.
// Each thread gathers blocks of 1024 rows (floats) to multiply.
double cpca_svd_bytes(double rows, double dim, double width, double threads) {
  const double qr = 3 * rows * width * 8;
  const double partials = rows * width * 8 + std::ceil(rows / kSvdBlockRows) * dim * width * 8;
  const double gather = threads * std::min(rows, kSvdBlockRows) * dim * 4;
  return std::max(qr, partials) + 2 * dim * width * 8 + gather;
}

}  // namespace

MemoryEstimate estimate_bake_memory(const MemoryEstimateInput& in) {
  const BakeSettings& b = in.bake;
  const double n = std::max(1, b.resolution);
  const double texels = n * n;
  const double threads = std::max(1, in.threads);
  Builder m{{}, kBaseProcessBytes, in.stages};
  const compress::CompressSettings& c = in.compression;
  // The compress stage compresses only when it runs and is enabled.
  const bool compressing = c.enabled && m.runs("compress");
  const bool keep_raw_tables = !compressing || c.keep_raw;
  // The parallax stage's form follows the same settings whether or not compress runs.
  const bool parallax_compressed = c.enabled, parallax_raw = !c.enabled || c.keep_raw;

  // load_fabric: the maps (and for image fabrics every decoded image at once).
  const double maps = kMapBytesPerTexel * texels;
  m.add("load_fabric", maps + (in.image_maps ? kImageBytesPerTexel * texels : 0.0), maps,
        "the feature maps", {"resolution"});
  m.add("fabric_records", 0, 0, "the fabric records", {});
  // feature_maps: a copy of every map as a section.
  m.add("feature_maps", maps, maps, "the feature map sections", {"resolution"});

  // parallax: 16-bit codes [dir][texel] while casting, then the stored forms.
  {
    const double d = double(b.parallax_dirs) * b.parallax_dirs * texels;  // texel-directions
    const double codes = 2 * d;
    double stored = 0, transient = 0;
    if (parallax_compressed) {
      // compress::hierarchical_parallax: 16-bit codes of every texel-direction, then the coded
      // stream and its sections. Kept: at most 2 bytes a texel-direction (an upper bound: the
      // example fabrics' streams are 0.3-0.9 bits a texel-direction).
      transient += 2 * d;
      stored += 2 * d;
    }
    if (parallax_raw) stored += 6 * d;  // codes and u32 SATs (raycast/raycast_sections)
    m.add("parallax", codes + kEmbreeBytesPerTexel * texels + transient + stored, stored,
          "the parallax codes of every texel and view direction", {"resolution", "parallax_dirs"});
  }

  // visibility: one bit per texel and direction, the ASG fit, its sections and decoded lobes.
  {
    const double words = std::ceil(double(b.visibility_dirs) * b.visibility_dirs / 64.0);
    const double samples = words * 8 * texels;
    const double kept = (kAsgBytesPerTexel + kLobeBytesPerTexel) * texels;
    // The grouping of texels by sample pattern (raycast/visibility.cpp): pattern index, first
    // texels (up to 8 bytes a texel while the vector grows) and hash slots (up to 16), and the
    // fits of the distinct patterns (a record and an error, at most one per texel).
    const double grouping = (28.0 + kAsgBytesPerTexel) * texels;
    m.add("visibility",
          samples + kEmbreeBytesPerTexel * texels + kAsgBytesPerTexel * texels + grouping + kept,
          kept, "the visibility samples of every texel and light direction",
          {"resolution", "visibility_dirs"});
  }

  // cluster: K-means over the lobes; labels and per-cluster mean visibility.
  {
    const double means = double(b.clusters) * b.visibility_dirs * b.visibility_dirs * 4;
    const double kept = kLabelBytesPerTexel * texels + means;
    m.add("cluster", kKmeansBytesPerTexel * texels + kept, kept, "the K-means of the lobes",
          {"resolution", "clusters"});
  }

  // tables: the raw fixed-point SATs (every cluster stored: an upper bound), or only the streaming
  // fills when nothing reads the raw tables.
  const double bins = double(b.radiance_dirs) * b.radiance_dirs;
  {
    const double element =
        tables::sat_element_bits(b.resolution, tables::RadianceOptions{}.max_relative_error) / 8.0;
    const double quadrature = bins * tables::kMaxSamplesPerBinSide / 2.0 *
                              tables::kMaxSamplesPerBinSide / 2.0 * 3 * 4;  // s <= 8
    if (keep_raw_tables) {
      const double sats = (bins + 1) * texels * double(b.clusters) * element;
      m.add("tables", sats + quadrature + kSggxBytesPerTexel * texels + threads * 4 * texels, sats,
            "the raw Integral-Radiance tables, one SAT per cluster and half-vector bin",
            {"resolution", "radiance_dirs", "clusters"});
    } else {
      const double fills =
          (kStreamedInputBytesPerTexel + 2 * kFillColumnBytesPerTexel + kSggxBytesPerTexel) *
              texels +
          quadrature;
      m.add("tables", fills, fills, "the streaming fills of the Integral-Radiance tables",
            {"resolution"});
    }
  }

  // compress: per kind (specular with every bin, then gap with one), the directional vectors of
  // every texel, the fill's blocks or the C-PCA, the compressed set.
  if (compressing) {
    const double values = 4 * texels * bins + texels;  // DirectionalTexels
    const double fill_blocks = keep_raw_tables ? 0.0 : threads * texels * kBinBlock * 4;
    // Target mode (the default) fits every cell at a rank cap of 16 first and refits at 32, 64, ...
    // only when cells saturate it without reaching the target (compress/cpca.cpp), which the
    // example fabrics never do (ranks 4 to 24); a fixed shape fits at its rank.
    const double cap = c.fixed ? double(c.rank) : std::min(double(c.rank), kTargetFirstRankCap);
    const double rank = std::min({cap, bins, texels});
    const double width = std::min({rank + kOversampling, bins, texels});
    // Rows: a C-PCA stratum is one visibility cluster; every texel in one is the upper bound.
    const double svd = cpca_svd_bytes(texels, bins, width, threads);
    const double coefficients = texels * rank * 4;  // every cell's float coefficients
    // The stored set: int16 coefficients, half basis and its float decode, the cell map, indices.
    const double images = std::min(4096.0, double(b.clusters) * c.clusters * (rank + 1));
    const double set = texels * rank * 2 + images * bins * (2 + 4) + texels * (1 + 4 + 8);
    const double working = values + std::max(fill_blocks, svd + coefficients + set);
    const double kept = texels * rank * 2 + images * bins * 2 + texels;
    std::vector<std::string> keys = {"resolution", "radiance_dirs"};
    m.add("compress", working, kept,
          "the per-texel directional vectors of the Integral-Radiance tables and their C-PCA",
          keys);
  } else {
    m.add("compress", 0, 0, "nothing (compression is off)", {});
  }

  // write: the metadata section; the sections are written from where the stages hold them.
  m.add("write", 1 << 20, 0, "the metadata", {});
  return m.out;
}

std::string format_bytes(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  double v = std::max(0.0, bytes);
  while (v >= 1024 && u < 6) {
    v /= 1024;
    ++u;
  }
  char text[32];
  if (u == 0)
    std::snprintf(text, sizeof text, "%.0f B", v);
  else
    std::snprintf(text, sizeof text,
                  v < 10    ? "%.2f %s"
                  : v < 100 ? "%.1f %s"
                            : "%.0f %s",
                  v, units[u]);
  return text;
}

nlohmann::json memory_estimate_json(const MemoryEstimate& e) {
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& s : e.stages)
    stages.push_back({{"name", s.stage},
                      {"peak_bytes", uint64_t(s.peak_bytes)},
                      {"working_bytes", uint64_t(s.working_bytes)},
                      {"keys", s.keys}});
  return {{"peak_bytes", uint64_t(e.peak_bytes)},
          {"peak_stage", e.stages.empty() ? "" : e.stages[e.peak_stage].stage},
          {"stages", stages}};
}

namespace {

std::string key_value(const BakeSettings& b, const std::string& key) {
  if (key == "resolution") return std::to_string(b.resolution);
  if (key == "parallax_dirs") return std::to_string(b.parallax_dirs);
  if (key == "visibility_dirs") return std::to_string(b.visibility_dirs);
  if (key == "radiance_dirs") return std::to_string(b.radiance_dirs);
  if (key == "clusters") return std::to_string(b.clusters);
  return "?";
}

}  // namespace

void check_memory_estimate(const MemoryEstimate& e, const BakeSettings& bake, double max_bytes,
                           const std::string& where) {
  if (e.stages.empty() || !(e.peak_bytes > max_bytes)) return;
  const StageMemory& s = e.stages[e.peak_stage];
  // The keys of the peak stage and of every earlier stage whose outputs are a large part of it
  // (the raw tables still resident while the compress stage runs), in the loader's key order.
  std::vector<std::string> named;
  for (std::size_t i = 0; i <= e.peak_stage; ++i)
    if (i == e.peak_stage || e.stages[i].kept_bytes >= 0.25 * e.peak_bytes)
      for (const auto& k : e.stages[i].keys)
        if (std::find(named.begin(), named.end(), k) == named.end()) named.push_back(k);
  const char* order[] = {"resolution", "parallax_dirs", "visibility_dirs", "radiance_dirs",
                         "clusters"};
  std::vector<std::string> sorted;
  for (const char* k : order)
    if (std::find(named.begin(), named.end(), k) != named.end()) sorted.push_back(k);
  std::string keys;
  for (const auto& k : sorted)
    keys += (keys.empty() ? "" : ", ") + k + " = " + key_value(bake, k);
  const std::string subject = keys.empty() ? "this bake needs" : "[bake] " + keys + " need";
  std::string lower;
  for (std::size_t i = 0; i < sorted.size(); ++i)
    lower += (i == 0 ? "" : i + 1 == sorted.size() ? " or " : ", ") + sorted[i];
  throw_input_error(where + ": " + subject + " ~" + format_bytes(e.peak_bytes) + " in the " +
                    s.stage + " stage (" + s.what + "); --max-memory is " +
                    format_bytes(max_bytes) + ": lower " +
                    (lower.empty() ? "the settings" : lower) + ", or raise --max-memory");
}

std::optional<MemoryEstimate> check_fabric_memory(const std::string& fabric_path,
                                                  const compress::CompressRequest& compression,
                                                  const std::vector<std::string>& stages,
                                                  int threads, uint64_t max_memory,
                                                  std::optional<int> resolution) {
  LoadOptions options;
  options.resolution = resolution;
  const auto peek = peek_fabric_settings(fabric_path, options);
  if (!peek) return std::nullopt;
  MemoryEstimateInput in;
  in.bake = peek->bake;
  in.compression = compress::resolve_compress_settings(peek->bake, compression);
  in.image_maps = peek->image_maps;
  in.threads = threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
  const auto list = bake_stages();
  try {
    for (const pipeline::Stage* s : pipeline::plan_stages(list, stages, {"fabric_path", "output"}))
      in.stages.push_back(s->name);
  } catch (const Error&) {
    in.stages.clear();  // an unknown stage name: every stage (the bake reports the name after)
  }
  MemoryEstimate estimate = estimate_bake_memory(in);
  check_memory_estimate(estimate, in.bake, double(max_memory), fabric_path);
  return estimate;
}

}  // namespace clothbake::stages

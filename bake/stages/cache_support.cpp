// Codecs of the algorithm artifact types and the colour-free fabric key view (cache_support.hpp).
// The static_asserts fail the build when an encoded struct gains a field.
#include "bake/stages/cache_support.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"

#include "bake/stages/table_streaming.hpp"

#include "cluster/visibility_clusters.hpp"
#include "compress/compress_settings.hpp"
#include "fabric/fabric.hpp"
#include "model/asg.hpp"

namespace clothbake::stages {
namespace {

using cache::ByteReader;
using cache::ByteWriter;

static_assert(sizeof(cluster::ClusterStats) == 40, "ClusterStats changed: update its codec");
static_assert(sizeof(cluster::KMeansResult) == 16 + 4 * 24 + 8 + 12 + 4,
              "KMeansResult changed: update its codec");
static_assert(sizeof(cluster::VisibilityClusters) ==
                  16 + 2 * 24 + 24 + 24 + sizeof(cluster::KMeansResult),
              "VisibilityClusters changed: update its codec");
static_assert(sizeof(compress::CompressRequest) == 8 + 8 + 8 + 16,
              "CompressRequest changed: update its codec");
static_assert(std::is_trivially_copyable_v<model::AsgParams<float>>);
static_assert(sizeof(tables::RadianceOptions) == 4 + 4 + 8 + 8,
              "RadianceOptions changed: update the tables/streamed codec");
static_assert(sizeof(StreamedTables) == 8 + sizeof(tables::RadianceOptions) + 6 * 24,
              "StreamedTables changed: update its codec");

// Decoded values are checked as values from a file would be (docs/batch.md, "Entries"): a crafted
// entry with correct checksums must fail here, as a corrupt entry (Error(Input)), not later.
void require(bool ok, const std::string& what) {
  if (!ok) throw_input_error(what);
}

template <class T>
bool all_finite(const std::vector<T>& v) {
  return std::all_of(v.begin(), v.end(), [](const T& x) { return std::isfinite(double(x)); });
}

// N^2 entries for a resolution N in [1, 16384] (the largest fabric, with room).
bool per_texel(int resolution, std::size_t size) {
  return resolution >= 1 && resolution <= 16384 && size == std::size_t(resolution) * resolution;
}

// The streaming fills are a function of their inputs and options: those are stored, the fills
// rebuilt on decode (cheap: no values are filled until the compress stage asks).
void encode_streamed(const StreamedTablesArtifact& t, ByteWriter& w) {
  w.pod(uint8_t(t != nullptr));
  if (!t) return;
  w.pod(int32_t(t->resolution));
  w.pod(int32_t(t->cluster_count));
  w.pod(int32_t(t->options.bins_per_side));
  w.pod(int32_t(t->options.samples_per_side));
  w.pod(t->options.max_relative_error);
  w.pod(uint8_t(t->options.warn_unresolved));
  w.vec(t->tangent);
  w.vec(t->gap);
  w.vec(t->yarn_id);
  w.vec(t->roughness);
  w.vec(t->labels);
}

StreamedTablesArtifact decode_streamed(ByteReader& r) {
  if (r.pod<uint8_t>() == 0) return nullptr;
  const int resolution = r.pod<int32_t>(), cluster_count = r.pod<int32_t>();
  tables::RadianceOptions options;
  options.bins_per_side = r.pod<int32_t>();
  options.samples_per_side = r.pod<int32_t>();
  options.max_relative_error = r.pod<double>();
  options.warn_unresolved = r.pod<uint8_t>() != 0;
  auto tangent = r.vec<Vec3f>();
  auto gap = r.vec<float>();
  auto yarn_id = r.vec<uint16_t>();
  auto roughness = r.vec<double>();
  auto labels = r.vec<uint8_t>();
  require(per_texel(resolution, tangent.size()) && gap.size() == tangent.size() &&
              yarn_id.size() == tangent.size() && labels.size() == tangent.size(),
          "streamed tables: inputs of other sizes than the resolution's");
  require(cluster_count >= 1 && cluster_count <= 255 &&
              std::all_of(labels.begin(), labels.end(),
                          [&](uint8_t l) { return int(l) < cluster_count; }),
          "streamed tables: a label outside the clusters");
  // samples_per_side 0 is the default rule (radiance_fill.hpp), what every bake writes.
  require(options.bins_per_side >= 1 && options.bins_per_side <= 1024 &&
              options.samples_per_side >= 0 && options.samples_per_side <= 1024 &&
              std::isfinite(options.max_relative_error),
          "streamed tables: options out of range");
  require(std::all_of(tangent.begin(), tangent.end(),
                      [](const Vec3f& t) {
                        return std::isfinite(t[0]) && std::isfinite(t[1]) && std::isfinite(t[2]);
                      }) &&
              all_finite(gap) && all_finite(roughness),
          "streamed tables: a value that is not finite");
  return make_streamed_tables(resolution, std::move(tangent), std::move(gap), std::move(yarn_id),
                              std::move(roughness), std::move(labels), cluster_count, options);
}

template <class T>
void put_optional(ByteWriter& w, const std::optional<T>& v) {
  w.pod(uint8_t(v.has_value()));
  w.pod(v.value_or(T{}));
}
template <class T>
std::optional<T> get_optional(ByteReader& r) {
  const bool has = r.pod<uint8_t>() != 0;
  const T v = r.pod<T>();
  return has ? std::optional<T>(v) : std::nullopt;
}

void encode_clusters(const cluster::VisibilityClusters& c, ByteWriter& w) {
  w.pod(int32_t(c.resolution));
  w.pod(int32_t(c.clusters));
  w.pod(int32_t(c.visibility_dirs));
  w.pod(int32_t(c.samples_per_bin_side));
  w.vec(c.labels);
  w.vec(c.mean_visibility);
  w.vec(c.stats);
  w.pod(c.variance);
  w.pod(c.residual_variance);
  w.pod(c.explained_fraction);
  const cluster::KMeansResult& k = c.kmeans;
  w.pod(int32_t(k.clusters));
  w.pod(uint64_t(k.dim));
  w.vec(k.labels);
  w.vec(k.centres);
  w.vec(k.sizes);
  w.vec(k.inertia);
  w.pod(k.total_inertia);
  w.pod(int32_t(k.iterations));
  w.pod(uint8_t(k.converged));
  w.pod(int32_t(k.empty_repairs));
}

cluster::VisibilityClusters decode_clusters(ByteReader& r) {
  cluster::VisibilityClusters c;
  c.resolution = r.pod<int32_t>();
  c.clusters = r.pod<int32_t>();
  c.visibility_dirs = r.pod<int32_t>();
  c.samples_per_bin_side = r.pod<int32_t>();
  c.labels = r.vec<uint8_t>();
  c.mean_visibility = r.vec<float>();
  c.stats = r.vec<cluster::ClusterStats>();
  c.variance = r.pod<double>();
  c.residual_variance = r.pod<double>();
  c.explained_fraction = r.pod<double>();
  cluster::KMeansResult& k = c.kmeans;
  k.clusters = r.pod<int32_t>();
  k.dim = std::size_t(r.pod<uint64_t>());
  k.labels = r.vec<int32_t>();
  k.centres = r.vec<double>();
  k.sizes = r.vec<uint64_t>();
  k.inertia = r.vec<double>();
  k.total_inertia = r.pod<double>();
  k.iterations = r.pod<int32_t>();
  k.converged = r.pod<uint8_t>() != 0;
  k.empty_repairs = r.pod<int32_t>();
  require(per_texel(c.resolution, c.labels.size()), "clusters: labels of another size");
  require(c.clusters >= 1 && c.clusters <= 255 &&
              std::all_of(c.labels.begin(), c.labels.end(),
                          [&](uint8_t l) { return int(l) < c.clusters; }),
          "clusters: a label outside the clusters");
  require(c.visibility_dirs >= 1 && c.visibility_dirs <= 1024 &&
              c.mean_visibility.size() ==
                  std::size_t(c.clusters) * c.visibility_dirs * c.visibility_dirs &&
              all_finite(c.mean_visibility) &&
              std::all_of(c.mean_visibility.begin(), c.mean_visibility.end(),
                          [](float v) { return v >= 0.f; }),
          "clusters: mean visibility of another size, negative or not finite");
  return c;
}

}  // namespace

cache::Codecs artifact_codecs() {
  cache::Codecs codecs;
  cache::add_basic_codecs(codecs);
  codecs.add<std::vector<model::AsgParams<float>>>(
      "asg_params/1",
      [](const std::vector<model::AsgParams<float>>& v, ByteWriter& w) { w.vec(v); },
      [](ByteReader& r) {
        std::vector<model::AsgParams<float>> v = r.vec<model::AsgParams<float>>();
        require(std::all_of(v.begin(), v.end(),
                            [](const model::AsgParams<float>& a) {
                              return std::isfinite(a.axis.x) && std::isfinite(a.axis.y) &&
                                     std::isfinite(a.axis.z) && std::isfinite(a.rotation) &&
                                     std::isfinite(a.lambda) && std::isfinite(a.mu) &&
                                     std::isfinite(a.amplitude);
                            }),
                "ASG lobes: a parameter that is not finite");
        return v;
      });
  codecs.add<cluster::VisibilityClusters>("visibility_clusters/1", encode_clusters,
                                          decode_clusters);
  codecs.add<StreamedTablesArtifact>("streamed_tables/1", encode_streamed, decode_streamed);
  codecs.add<compress::CompressRequest>(
      "compress_request/1",
      [](const compress::CompressRequest& q, ByteWriter& w) {
        w.pod(uint8_t(q.disable));
        w.pod(uint8_t(q.keep_raw));
        put_optional(w, q.clusters);
        put_optional(w, q.rank);
        put_optional(w, q.max_error);
      },
      [](ByteReader& r) {
        compress::CompressRequest q;
        q.disable = r.pod<uint8_t>() != 0;
        q.keep_raw = r.pod<uint8_t>() != 0;
        q.clusters = get_optional<int>(r);
        q.rank = get_optional<int>(r);
        q.max_error = get_optional<double>(r);
        return q;
      });
  return codecs;
}

void fabric_without_colours_view(const pipeline::Artifacts& available, pipeline::Artifacts& view) {
  Fabric f = available.get<Fabric>("fabric");
  f.name.clear();
  f.inputs.clear();
  f.maps.albedo.clear();
  for (auto& y : f.yarns) {
    y.name.clear();
    y.specular_albedo = Rgb{};
    y.diffuse_reflectance = Rgb{};
    y.diffuse_transmittance = Rgb{};
    y.color = Rgb{};
  }
  f.sheen = SheenParams{};
  view.put("fabric", std::move(f));
}

}  // namespace clothbake::stages

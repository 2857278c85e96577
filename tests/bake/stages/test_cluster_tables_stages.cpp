// The `cluster` and `tables` pipeline stages in process: seeded with a fabric and visibility
// lobes, they produce the label map, mean visibility and raw tables as sections the reader
// accepts, the same bytes for 1 and 2 threads, and record the 2-sigma verdict in the metadata.
#include <gtest/gtest.h>

#include <cstring>
#include <utility>

#include <algorithm>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/driver.hpp"
#include "bake/pipeline/stage.hpp"
#include "bake/stages/stages.hpp"
#include "bake/stages/table_streaming.hpp"
#include "cluster/visibility_clusters.hpp"
#include "compress/compress_settings.hpp"
#include "formats/reader/cluster_sections.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/asset_writer.hpp"

using namespace clothbake;

namespace {

std::vector<pipeline::Stage> my_stages() {
  return {stages::cluster_stage(), stages::tables_stage()};
}

pipeline::Artifacts seeded(double roughness) {
  Fabric f = fabric_from_named_weave("twill2/1", 16).fabric;
  for (auto& y : f.yarns)
    y.roughness = roughness;
  f.bake.radiance_dirs = 8;
  f.bake.visibility_dirs = 8;
  f.bake.clusters = 4;
  std::vector<model::AsgParams<float>> lobes;
  for (int i = 0; i < 16 * 16; ++i) {  // four visibility types, by rows
    const float type = float(i / 16 % 4);
    lobes.push_back({model::normalize(model::Vec3f(0.3f * type - 0.45f, 0.0f, 1.0f)), 0.0f,
                     5.0f * type, 1.0f, 1.0f});
  }
  pipeline::Artifacts a;
  a.put("fabric", std::move(f));
  a.put("visibility/asg_params", std::move(lobes));
  return a;
}

std::vector<std::byte> asset_bytes(const pipeline::RunResult& r) {
  std::vector<formats::Section> all;
  for (const char* name : {"section/clusters", "section/tables"})
    for (const auto& s : r.artifacts.get<std::vector<formats::Section>>(name))
      all.push_back(s);
  return formats::serialize_asset(all);
}

}  // namespace

TEST(TablesStages, ProduceReadableSectionsDeterministically) {
  const auto stages = my_stages();
  ASSERT_EQ(stages.size(), 2u);
  pipeline::RunOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto r1 = pipeline::run_pipeline({"tables"}, seeded(0.3), one, stages);
  const auto r2 = pipeline::run_pipeline({"tables"}, seeded(0.3), two, stages);
  const auto b1 = asset_bytes(r1), b2 = asset_bytes(r2);
  EXPECT_TRUE(b1 == b2);
  reader::Asset asset;
  ASSERT_TRUE(asset.open_memory(b1.data(), b1.size()).ok());
  reader::VisibilityClusterView clusters;
  ASSERT_TRUE(clusters.open(asset).ok());
  // Four visibility types, each split into its warp and its weft texels (clusters_by_yarn): no
  // cluster mixes yarns.
  EXPECT_EQ(clusters.cluster_count(), 8u);
  EXPECT_EQ(clusters.visibility_dirs(), 8u);
  const pipeline::Artifacts inputs = seeded(0.3);
  const Fabric& fabric = inputs.get<Fabric>("fabric");
  std::vector<int> yarn_of(8, -1);
  for (int t = 0; t < 16 * 16; ++t) {
    int& y = yarn_of[clusters.label(t % 16, t / 16)];
    if (y < 0) y = fabric.maps.yarn_id[t];
    EXPECT_EQ(y, fabric.maps.yarn_id[t]) << "texel " << t;
  }
  // The visibility basis: rank 4 of the clusters' 8^2-bin visibility, a coefficient per texel.
  reader::VisibilityBasisView basis;
  ASSERT_TRUE(basis.open(asset).ok());
  EXPECT_EQ(basis.cluster_count(), 8u);
  EXPECT_EQ(basis.rank(), 4u);
  EXPECT_EQ(basis.dirs(), 8u);
  EXPECT_EQ(basis.resolution(), 16u);
  // Values outside the ranges the definitions give (a mean in [0, 1], a unit vector's entries in
  // [-1, 1], a coefficient within the grid's side of 0) are refused even when finite: a coefficient
  // near the float maximum once overflowed the evaluator's sums (the C interface's fuzzer).
  {
    reader::ArrayView<float> components, coefficients;
    ASSERT_TRUE(asset.array(reader::SectionType::ClusterVisibilityBasis, 0, &components).ok());
    ASSERT_TRUE(asset.array(reader::SectionType::ClusterVisibilityBasis, 1, &coefficients).ok());
    const auto at = [&](const float* p) {
      return std::size_t(reinterpret_cast<const std::byte*>(p) - b1.data());
    };
    const std::size_t mean0 = at(components.data), unit0 = at(components.data + 8 * 8),
                      coefficient0 = at(coefficients.data);
    for (const auto& [offset, value] :
         std::vector<std::pair<std::size_t, float>>{{mean0, -0.5f},
                                                    {mean0, 1.5f},
                                                    {unit0, 1.5f},
                                                    {unit0, -1.5f},
                                                    {coefficient0, 9.0f},
                                                    {coefficient0, -3.0e38f}}) {
      std::vector<std::byte> bad = b1;
      std::memcpy(bad.data() + offset, &value, 4);
      reader::Asset damaged;
      ASSERT_TRUE(damaged.open_memory(bad.data(), bad.size()).ok());
      reader::VisibilityBasisView view;
      const reader::Status st = view.open(damaged);
      EXPECT_EQ(st.code(), reader::ErrorCode::Malformed) << offset << " " << value;
      EXPECT_STREQ(st.check_id(), "CBK-E021") << st.message();
    }
    // In range: 8 (the grid's side) for a coefficient, 1 for a unit vector's entry.
    std::vector<std::byte> fine = b1;
    const float eight = 8.0f, one = 1.0f;
    std::memcpy(fine.data() + coefficient0, &eight, 4);
    std::memcpy(fine.data() + unit0, &one, 4);
    reader::Asset edited;
    ASSERT_TRUE(edited.open_memory(fine.data(), fine.size()).ok());
    reader::VisibilityBasisView view;
    EXPECT_TRUE(view.open(edited).ok());
  }
  reader::RawRadianceTables spec;
  ASSERT_TRUE(spec.open(asset, reader::RadianceTableKind::Specular).ok());
  EXPECT_EQ(spec.bins_per_side(), 8u);
  EXPECT_TRUE(spec.check_contents().ok());
  const auto& meta = r1.artifacts.get<nlohmann::json>("metadata/tables");
  EXPECT_EQ(meta["radiance_dirs"], 8);
  EXPECT_EQ(meta["resolved"], true);  // 8^2 bins resolve roughness 0.3 (2-sigma rule: n >= 5)
  EXPECT_EQ(meta["radiance_dirs_needed"], 5);
  const auto& cmeta = r1.artifacts.get<nlohmann::json>("metadata/clusters");
  EXPECT_EQ(cmeta["clusters"], 8);
  EXPECT_GT(cmeta["explained_fraction"].get<double>(), 0.99);  // four exact visibility types
  // A satin-like roughness against 8^2 bins: recorded as unresolved, with the bins it needs.
  const auto narrow = pipeline::run_pipeline({"tables"}, seeded(0.05), two, stages);
  const auto& nmeta = narrow.artifacts.get<nlohmann::json>("metadata/tables");
  EXPECT_EQ(nmeta["resolved"], false);
  EXPECT_EQ(nmeta["radiance_dirs_needed"], 26);
}

namespace {

// A compressing bake of the seeded fabric up to the compress stage, with some texels partly gap
// so that both table kinds exist; keep_raw asks for the raw tables too (no streaming).
pipeline::RunResult compress_run(bool keep_raw, int threads) {
  pipeline::Artifacts a = seeded(0.3);
  {
    Fabric f = a.get<Fabric>("fabric");
    for (std::size_t t = 0; t < f.maps.gap.size(); t += 5)
      f.maps.gap[t] = 0.25f * float(t % 4);
    pipeline::Artifacts b;
    b.put("fabric", std::move(f));
    b.put("visibility/asg_params",
          a.get<std::vector<model::AsgParams<float>>>("visibility/asg_params"));
    a = std::move(b);
  }
  if (keep_raw) {
    compress::CompressRequest request;
    request.keep_raw = true;
    a.put(stages::kCompressSettingsArtifact, request);
  }
  pipeline::RunOptions options;
  options.threads = threads;
  const std::vector<pipeline::Stage> stages = {stages::cluster_stage(), stages::tables_stage(),
                                               stages::compress_stage()};
  return pipeline::run_pipeline({"compress"}, std::move(a), options, stages);
}

std::vector<std::byte> section_bytes(const pipeline::RunResult& r, const char* name) {
  return formats::serialize_asset(r.artifacts.get<std::vector<formats::Section>>(name));
}

}  // namespace

// Without --keep-raw the raw SATs are never built (an empty raw section list, the streaming fills
// instead), and the compressed sections are the bytes the raw path gives, for 1 and 2 threads.
TEST(TablesStages, StreamingIntoTheCompressionGivesTheRawPathsBytes) {
  const auto streamed = compress_run(false, 2);
  const auto streamed1 = compress_run(false, 1);
  const auto raw = compress_run(true, 2);
  EXPECT_TRUE(streamed.artifacts.get<std::vector<formats::Section>>("section/tables").empty());
  EXPECT_FALSE(raw.artifacts.get<std::vector<formats::Section>>("section/tables").empty());
  const auto& plan =
      streamed.artifacts.get<stages::StreamedTablesArtifact>(stages::kStreamedTablesArtifact);
  ASSERT_TRUE(plan);
  EXPECT_EQ(plan->fills.size(), 2u);  // specular and gap
  EXPECT_FALSE(raw.artifacts.get<stages::StreamedTablesArtifact>(stages::kStreamedTablesArtifact));
  const auto compressed = section_bytes(streamed, "section/compress");
  EXPECT_GT(compressed.size(), 1000u);
  EXPECT_TRUE(compressed == section_bytes(raw, "section/compress"));
  EXPECT_TRUE(compressed == section_bytes(streamed1, "section/compress"));
  // The table metadata does not depend on the path (it is part of the asset's bytes).
  EXPECT_EQ(streamed.artifacts.get<nlohmann::json>("metadata/tables"),
            raw.artifacts.get<nlohmann::json>("metadata/tables"));
  EXPECT_EQ(streamed.artifacts.get<std::vector<std::string>>(stages::kCompressSupersedesArtifact),
            std::vector<std::string>{"section/tables"});
}

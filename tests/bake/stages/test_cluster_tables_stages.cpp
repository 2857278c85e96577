// The `cluster` and `tables` pipeline stages in process: seeded with a fabric and visibility
// lobes, they produce the label map, mean visibility and raw tables as sections the reader
// accepts, the same bytes for 1 and 2 threads, and record the 2-sigma verdict in the metadata.
#include <gtest/gtest.h>

#include <algorithm>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/driver.hpp"
#include "bake/pipeline/stage.hpp"
#include "bake/stages/stages.hpp"
#include "cluster/visibility_clusters.hpp"
#include "formats/reader/cluster_sections.hpp"
#include "formats/reader/radiance_tables.hpp"
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
  EXPECT_EQ(clusters.cluster_count(), 4u);
  EXPECT_EQ(clusters.visibility_dirs(), 8u);
  reader::RawRadianceTables spec;
  ASSERT_TRUE(spec.open(asset, reader::RadianceTableKind::Specular).ok());
  EXPECT_EQ(spec.bins_per_side(), 8u);
  EXPECT_TRUE(spec.check_contents().ok());
  const auto& meta = r1.artifacts.get<nlohmann::json>("metadata/tables");
  EXPECT_EQ(meta["radiance_dirs"], 8);
  EXPECT_EQ(meta["resolved"], true);  // 8^2 bins resolve roughness 0.3 (2-sigma rule: n >= 5)
  EXPECT_EQ(meta["radiance_dirs_needed"], 5);
  const auto& cmeta = r1.artifacts.get<nlohmann::json>("metadata/clusters");
  EXPECT_EQ(cmeta["clusters"], 4);
  EXPECT_GT(cmeta["explained_fraction"].get<double>(), 0.99);  // four exact visibility types
  // A satin-like roughness against 8^2 bins: recorded as unresolved, with the bins it needs.
  const auto narrow = pipeline::run_pipeline({"tables"}, seeded(0.05), two, stages);
  const auto& nmeta = narrow.artifacts.get<nlohmann::json>("metadata/tables");
  EXPECT_EQ(nmeta["resolved"], false);
  EXPECT_EQ(nmeta["radiance_dirs_needed"], 26);
}

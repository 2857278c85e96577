// fabric/fabric_json.hpp: every BakeSettings field under its [bake] key, and the asset metadata
// (fabric_metadata) using exactly that form.
#include <gtest/gtest.h>

#include "fabric/fabric_json.hpp"
#include "fabric/fabric_sections.hpp"

namespace {

using namespace clothbake;

BakeSettings unusual_settings() {
  BakeSettings b;
  b.resolution = 64;
  b.parallax_dirs = 9;
  b.parallax_min_cos = 0.625;
  b.parallax_max_error = 0.125;
  b.visibility_dirs = 11;
  b.radiance_dirs = 13;
  b.clusters = 5;
  b.clusters_by_yarn = false;
  b.visibility_rank = 9;
  b.compress = false;
  b.compress_clusters = 3;
  b.compress_rank = 7;
  b.seed = 0xffffffffffffffffull;  // needs the unsigned JSON number
  return b;
}

TEST(BakeSettingsJson, HoldsEveryFieldUnderItsTomlKey) {
  const nlohmann::json j = bake_settings_json(unusual_settings());
  const nlohmann::json expected = {{"resolution", 64},
                                   {"parallax_dirs", 9},
                                   {"parallax_min_cos", 0.625},
                                   {"parallax_max_error", 0.125},
                                   {"visibility_dirs", 11},
                                   {"radiance_dirs", 13},
                                   {"clusters", 5},
                                   {"clusters_by_yarn", false},
                                   {"visibility_rank", 9},
                                   {"compress", false},
                                   {"compress_clusters", 3},
                                   {"compress_rank", 7},
                                   {"seed", 0xffffffffffffffffull}};
  EXPECT_EQ(j, expected);
  EXPECT_TRUE(j["seed"].is_number_unsigned());
}

TEST(BakeSettingsJson, IsWhatTheAssetMetadataStores) {
  Fabric fabric;
  fabric.name = "test";
  fabric.bake = unusual_settings();
  EXPECT_EQ(fabric_metadata(fabric)["bake"], bake_settings_json(fabric.bake));
}

}  // namespace

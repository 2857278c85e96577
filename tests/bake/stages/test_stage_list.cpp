// bake/stages/stage_list.cpp: the one list of the bake's stages is the order a full bake runs
// them. The driver derives the order from the stages' inputs and outputs (ties by name); if a
// stage is added to the list at the wrong place, or its inputs change, this test says where it
// belongs instead of letting the list lie.
#include <gtest/gtest.h>

#include <set>

#include "bake/pipeline/plan.hpp"
#include "bake/stages/stages.hpp"

namespace {

using namespace clothbake;

std::vector<std::string> names_of(const std::vector<pipeline::Stage>& list) {
  std::vector<std::string> out;
  for (const auto& s : list)
    out.push_back(s.name);
  return out;
}

TEST(StageList, IsTheRunOrderOfAFullBake) {
  const std::vector<pipeline::Stage> list = stages::bake_stages();
  std::vector<std::string> planned;
  for (const pipeline::Stage* s : pipeline::plan_stages(list, {}, {"fabric_path", "output"}))
    planned.push_back(s->name);
  EXPECT_EQ(planned, names_of(list));
}

TEST(StageList, NamesEveryStageOnceAndInTheDocumentedOrder) {
  const auto names = names_of(stages::bake_stages());
  EXPECT_EQ(names,
            (std::vector<std::string>{"load_fabric", "fabric_records", "feature_maps", "parallax",
                                      "visibility", "cluster", "tables", "compress", "write"}));
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  for (const auto& s : stages::bake_stages())
    EXPECT_TRUE(static_cast<bool>(s.run)) << s.name;
}

}  // namespace

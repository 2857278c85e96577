// Scene planning (bake/reports/scene_plan.hpp) in process, on usages built by hand: each rule of
// plan_fabric follows the usage it is given (light behind the cloth or not, the half-vector bins
// and view directions the scene touches, footprint sizes) and the plan's estimate shrinks with
// what it leaves out; an object no pixel sees needs nothing. The same rules through the
// executable and a real usage analysis: tests/render/test_scene_plans.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "bake/reports/scene_plan.hpp"
#include "render/usage_analysis.hpp"

using namespace clothbake;

namespace {

const reports::PlanDecision* decision(const reports::FabricPlan& p, const std::string& item) {
  for (const auto& d : p.decisions)
    if (d.item == item) return &d;
  return nullptr;
}

// A usage of `fabric` seen by 1000 pixels with footprints of `side` texels, lit from the front,
// touching every half-vector bin and view direction.
render::ObjectUsage front_lit(const Fabric& fabric, double side) {
  render::ObjectUsage u;
  u.object = 0;
  u.pixels = 1000;
  u.footprint_min = u.footprint_p05 = u.footprint_median = u.footprint_max = side;
  u.min_view_cos = 0.5;
  u.views_front = true;
  u.lit_same_side = 1000;
  u.min_light_cos = 0.5;
  u.half_vector_bins.assign(std::size_t(fabric.bake.radiance_dirs) * fabric.bake.radiance_dirs, 1);
  u.max_half_vector_angle = 1.0;
  u.view_bins.assign(std::size_t(fabric.bake.parallax_dirs) * fabric.bake.parallax_dirs, 1);
  return u;
}

}  // namespace

TEST(ScenePlan, TransmissionFollowsTheLightBehindTheCloth) {
  const Fabric fabric = fabric_from_named_weave("twill2/1", 32).fabric;
  render::ObjectUsage u = front_lit(fabric, 1.0);
  const reports::FabricPlan front = reports::plan_fabric(fabric, u, 0.008);
  ASSERT_NE(decision(front, "transmission and gap tables"), nullptr);
  EXPECT_EQ(decision(front, "transmission and gap tables")->decision, "left out");
  u.lit_opposite_side = 10;
  const reports::FabricPlan back = reports::plan_fabric(fabric, u, 0.008);
  EXPECT_EQ(decision(back, "transmission and gap tables")->decision, "kept");
  // Leaving the transmission tables out makes the planned asset smaller than the full one.
  EXPECT_LT(front.estimate.planned_bytes, back.estimate.planned_bytes);
  EXPECT_EQ(front.estimate.full_bytes, back.estimate.full_bytes);
}

TEST(ScenePlan, BinsAndViewDirectionsAreReducedToWhatTheSceneTouches) {
  const Fabric fabric = fabric_from_named_weave("twill2/1", 32).fabric;
  render::ObjectUsage all = front_lit(fabric, 1.0);
  const reports::FabricPlan full = reports::plan_fabric(fabric, all, 0.008);
  EXPECT_EQ(decision(full, "half-vector bins")->decision, "kept");
  EXPECT_EQ(decision(full, "parallax view directions")->decision, "kept");

  render::ObjectUsage some = all;
  std::fill(some.half_vector_bins.begin(), some.half_vector_bins.end(), 0);
  some.half_vector_bins[0] = some.half_vector_bins[1] = 1;
  std::fill(some.view_bins.begin(), some.view_bins.end(), 0);
  some.view_bins[0] = 1;
  const reports::FabricPlan reduced = reports::plan_fabric(fabric, some, 0.008);
  EXPECT_EQ(decision(reduced, "half-vector bins")->decision, "reduced");
  EXPECT_NE(decision(reduced, "half-vector bins")->reason.find("2 of "), std::string::npos)
      << decision(reduced, "half-vector bins")->reason;
  EXPECT_EQ(decision(reduced, "parallax view directions")->decision, "reduced");
  // The kept view directions are closed under the hierarchical parallax's references, and
  // include the one the views touch.
  EXPECT_EQ(reduced.usage.view_bins[0], 1);
  EXPECT_LT(reduced.usage.view_bins_used(), all.view_bins_used());
  EXPECT_LT(reduced.estimate.planned_bytes, full.estimate.planned_bytes);
  EXPECT_LT(reduced.estimate.planned_seconds, full.estimate.planned_seconds);
}

TEST(ScenePlan, WideFootprintsNeedNeitherPerTexelParallaxNorFineVisibility) {
  const Fabric fabric = fabric_from_named_weave("twill2/1", 32).fabric;
  const reports::FabricPlan near = reports::plan_fabric(fabric, front_lit(fabric, 1.0), 0.008);
  EXPECT_EQ(decision(near, "per-texel parallax")->decision, "kept");
  EXPECT_EQ(decision(near, "visibility directions")->decision, "kept");
  EXPECT_EQ(near.visibility_dirs, fabric.bake.visibility_dirs);
  const reports::FabricPlan far = reports::plan_fabric(fabric, front_lit(fabric, 1e6), 0.008);
  EXPECT_EQ(decision(far, "per-texel parallax")->decision, "left out");
  EXPECT_EQ(decision(far, "visibility directions")->decision, "reduced");
  EXPECT_LT(far.visibility_dirs, fabric.bake.visibility_dirs);
}

TEST(ScenePlan, AnObjectNoPixelSeesNeedsNothing) {
  const Fabric fabric = fabric_from_named_weave("twill2/1", 32).fabric;
  render::ObjectUsage u = front_lit(fabric, 1.0);
  u.pixels = 0;
  const reports::FabricPlan p = reports::plan_fabric(fabric, u, 0.008);
  EXPECT_TRUE(p.decisions.empty());
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_NE(p.warnings[0].find("no pixel sees this object"), std::string::npos);
  // plan_json carries every decision of every fabric.
  reports::ScenePlan plan;
  plan.scene = "s.toml";
  plan.max_error = 0.008;
  plan.fabrics.push_back(reports::plan_fabric(fabric, front_lit(fabric, 1.0), 0.008));
  const nlohmann::json doc = reports::plan_json(plan);
  ASSERT_EQ(doc["fabrics"].size(), 1u);
  EXPECT_EQ(doc["fabrics"][0]["decisions"].size(), plan.fabrics[0].decisions.size());
}

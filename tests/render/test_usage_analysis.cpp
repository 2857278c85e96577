// The usage analysis of a scene (render/usage_analysis.hpp) against closed forms and the rules a
// scene-driven bake relies on: a distant camera gives large footprints, a light in front never
// lights the back, one camera and one distant light reach a handful of half-vector bins (the one
// of the mirror half vector among them), a grazing camera is seen as grazing, a blocker shadows,
// and the result is the same for any thread count.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "formats/reader/radiance_query.hpp"
#include "render/usage_analysis.hpp"

namespace clothbake::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A 4 x 4 plane at the origin facing +z, seen head-on from distance d.
Scene plane_scene(double distance, int pixels) {
  Scene s;
  s.camera.position = {0, 0, distance};
  s.camera.look_at = {0, 0, 0};
  s.camera.up = {0, 1, 0};
  s.camera.fov_deg = 30;
  s.camera.width = s.camera.height = pixels;
  Object plane;
  plane.name = "object[0]";
  plane.shape = ShapeType::Plane;
  plane.size[0] = plane.size[1] = 4;
  plane.tiles_per_unit = 2;
  s.objects.push_back(plane);
  return s;
}

Light directional(Vec3 travel) {
  Light l;
  l.type = LightType::Directional;
  l.direction = normalize(travel);
  return l;
}

const std::vector<FabricShape> kShape = {{64, 16}};

TEST(UsageAnalysis, FootprintOfAHeadOnPlaneIsThePixelSize) {
  for (const double d : {2.0, 20.0}) {
    Scene s = plane_scene(d, 33);
    s.camera.fov_deg = 2 * std::atan(1.5 / d) * 180 / kPi;  // the plane fills the view
    s.lights.push_back(directional({0, 0, -1}));
    const SceneUsage u = analyse_usage(s, kShape);
    const ObjectUsage& o = u.objects[0];
    EXPECT_EQ(o.pixels, 33u * 33u);
    // Centre pixel: 2 d tan(fov / 2) / H world units = 3 / 33, times tiles_per_unit * N texels;
    // off-axis pixels are larger (1 / cos^3 in area), never smaller.
    const double side = 3.0 / 33 * 2 * 64;
    EXPECT_NEAR(o.footprint_min, side, 1e-4 * side) << d;
    EXPECT_GE(o.footprint_median, o.footprint_min);
    EXPECT_LT(o.footprint_max, side * std::pow(1 + 1.5 * 1.5 * 2 / (d * d), 0.75) * 1.0001) << d;
  }
  // A distant camera with a narrow view of the whole plane: every footprint is large.
  Scene far = plane_scene(200, 16);
  far.camera.fov_deg = 2;
  far.lights.push_back(directional({0, 0, -1}));
  EXPECT_GT(analyse_usage(far, kShape).objects[0].footprint_min, 12.0);
}

TEST(UsageAnalysis, ALightInFrontNeverLightsTheBack) {
  Scene s = plane_scene(3, 16);
  s.lights.push_back(directional({0.3, 0.2, -1}));  // travels towards -z: lights the front
  const ObjectUsage front = analyse_usage(s, kShape).objects[0];
  EXPECT_GT(front.lit_same_side, 0u);
  EXPECT_EQ(front.lit_opposite_side, 0u);
  EXPECT_FALSE(front.back_lit());
  EXPECT_TRUE(front.views_front);
  EXPECT_FALSE(front.views_back);
  s.lights.push_back(directional({0.1, 0, 1}));  // from behind the cloth
  const ObjectUsage both = analyse_usage(s, kShape).objects[0];
  EXPECT_TRUE(both.back_lit());
  EXPECT_EQ(both.lit_opposite_side, both.pixels);
}

TEST(UsageAnalysis, OneCameraAndOneDistantLightReachAFewHalfVectorBins) {
  Scene s = plane_scene(40, 8);
  s.camera.fov_deg = 1;  // nearly parallel views straight down
  const Vec3 travel = normalize(Vec3(-0.5, 0, -1));
  s.lights.push_back(directional(travel));
  const ObjectUsage o = analyse_usage(s, kShape).objects[0];
  ASSERT_EQ(o.half_vector_bins.size(), 256u);
  EXPECT_GE(o.half_vector_bins_used(), 1u);
  EXPECT_LE(o.half_vector_bins_used(), 8u);  // the bilinear support of nearly one h
  // The mirror half vector h = wi + wo, wo = +z, wi = -travel: its bins are among the used ones.
  const Vec3 hv = Vec3(0, 0, 1) - travel;
  const double harr[3] = {hv.x, hv.y, hv.z};
  reader::BinWeights bw;
  ASSERT_TRUE(reader::make_bin_weights(16, harr, &bw));
  for (uint32_t j = 0; j < bw.count; ++j)
    if (bw.weight[j] > 1e-3) {
      EXPECT_EQ(o.half_vector_bins[bw.bin[j]], 1) << bw.bin[j];
    }
  const double angle = std::acos(normalize(hv).z);
  EXPECT_NEAR(o.max_half_vector_angle, angle, 0.01);
}

TEST(UsageAnalysis, AGrazingCameraIsGrazing) {
  Scene s = plane_scene(3, 16);
  s.camera.position = {0, -6, 0.3};  // about 3 degrees above the plane at its centre
  s.camera.fov_deg = 10;
  s.lights.push_back(directional({0, 0, -1}));
  const ObjectUsage o = analyse_usage(s, kShape).objects[0];
  ASSERT_GT(o.pixels, 0u);
  EXPECT_LT(o.min_view_cos, 0.1);
  EXPECT_GT(o.grazing_view_fraction, 0.9);
  const ObjectUsage head_on = analyse_usage(plane_scene(3, 16), kShape).objects[0];
  EXPECT_EQ(head_on.grazing_view_fraction, 0.0);
}

TEST(UsageAnalysis, ABlockerShadowsAndAnEnvironmentLightsBothSides) {
  Scene s = plane_scene(3, 16);
  s.camera.fov_deg = 10;
  s.lights.push_back(directional({0, 0, -1}));
  Object roof;  // a larger plane between the light and the cloth, above the camera
  roof.name = "object[1]";
  roof.shape = ShapeType::Plane;
  roof.center = {0, 0, 5};
  roof.size[0] = roof.size[1] = 10;
  s.objects.push_back(roof);
  const std::vector<FabricShape> shapes = {{64, 16}, {0, 0}};
  const ObjectUsage shadowed = analyse_usage(s, shapes).objects[0];
  EXPECT_GT(shadowed.pixels, 0u);
  EXPECT_EQ(shadowed.lit_same_side + shadowed.lit_opposite_side, 0u);
  // A constant environment instead: both sides lit (directions below the plane reach its back).
  Scene e = plane_scene(3, 8);
  Light env;
  env.type = LightType::Environment;
  env.environment.width = 4;
  env.environment.height = 2;
  env.environment.rgb.assign(4 * 2 * 3, 1.0f);
  e.lights.push_back(env);
  const ObjectUsage lit = analyse_usage(e, kShape).objects[0];
  EXPECT_GT(lit.lit_same_side, 0u);
  EXPECT_TRUE(lit.back_lit());
  EXPECT_GT(lit.half_vector_bins_used(), 128u);  // most of the 16^2 bins
}

TEST(UsageAnalysis, IsTheSameForAnyThreadCount) {
  Scene s = plane_scene(2.5, 40);
  s.camera.position = {1, -2, 1.5};
  s.lights.push_back(directional({0.3, 0.5, -1}));
  Light point;
  point.type = LightType::Point;
  point.position = {-1, 1, 0.5};
  s.lights.push_back(point);
  SceneUsage one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = analyse_usage(s, kShape);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = analyse_usage(s, kShape);
  }
  const ObjectUsage &a = one.objects[0], &b = two.objects[0];
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_EQ(a.footprint_min, b.footprint_min);
  EXPECT_EQ(a.footprint_median, b.footprint_median);
  EXPECT_EQ(a.half_vector_bins, b.half_vector_bins);
  EXPECT_EQ(a.lit_same_side, b.lit_same_side);
  EXPECT_EQ(a.max_half_vector_angle, b.max_half_vector_angle);
}

}  // namespace
}  // namespace clothbake::render

// The renderer against closed forms and its own properties (render/renderer.hpp).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "bake/inputs/scene_load.hpp"
#include "render/environment.hpp"
#include "render/renderer.hpp"
#include "tests/eval/eval_fixtures.hpp"

namespace clothbake::render {
namespace {

using eval_test::assets;
constexpr double kPi = 3.14159265358979323846;

Scene plane_scene(int w, int h) {
  Scene s;
  s.camera.position = {0, 0, 2};
  s.camera.look_at = {0, 0, 0};
  s.camera.up = {0, 1, 0};
  s.camera.fov_deg = 30;
  s.camera.width = w;
  s.camera.height = h;
  Object plane;
  plane.name = "object[0]";
  plane.shape = ShapeType::Plane;
  plane.normal = {0, 0, 1};
  plane.tangent = {1, 0, 0};
  plane.size[0] = plane.size[1] = 4;
  plane.diffuse = Rgb(0.6, 0.4, 0.2);
  s.objects.push_back(plane);
  return s;
}

TEST(Render, LambertianPlaneUnderADirectionalLightIsTheClosedForm) {
  Scene s = plane_scene(16, 16);
  Light sun;
  sun.type = LightType::Directional;
  sun.direction = normalize(Vec3(0.3, -0.2, -0.9));
  sun.irradiance = Rgb(2.0, 3.0, 4.0);
  s.lights.push_back(sun);
  const RenderResult r = Renderer(s, {}).render();
  const double cos_theta = -sun.direction.z;
  for (int k = 0; k < 16 * 16; ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(r.rgb[3 * k + c], s.objects[0].diffuse[c] / kPi * sun.irradiance[c] * cos_theta,
                  1e-6);
}

TEST(Render, WhiteFurnaceUnderAConstantEnvironment) {
  // A Lambertian plane under a constant sky: radiance rho L, whatever MIS does (within 3 SE).
  Scene s = plane_scene(8, 8);
  s.objects[0].diffuse = Rgb(0.5);
  s.objects[0].size[0] = s.objects[0].size[1] = 1e6;  // fills the lower hemisphere: no sky below
  Light sky;
  sky.type = LightType::Environment;
  sky.environment.width = 32;
  sky.environment.height = 16;
  sky.environment.rgb.assign(32 * 16 * 3, 2.0f);
  s.lights.push_back(sky);
  RenderOptions o;
  o.spp = 64;
  const RenderResult r = Renderer(s, o).render();
  double sum = 0, sum2 = 0;
  for (int k = 0; k < 64; ++k) {
    sum += r.rgb[3 * k];
    sum2 += r.rgb[3 * k] * r.rgb[3 * k];
  }
  const double mean = sum / 64, se = std::sqrt((sum2 / 64 - mean * mean) / 63);
  EXPECT_NEAR(mean, 0.5 * 2.0, 3 * se + 1e-12);
}

TEST(Render, EnvironmentSamplingDensityIntegratesToOne) {
  EnvironmentMap map;
  map.width = 16;
  map.height = 8;
  for (int k = 0; k < 16 * 8; ++k)
    for (int c = 0; c < 3; ++c)
      map.rgb.push_back(float(1 + (k * 7 % 5)));
  const Environment env(map);
  // Integral of pdf over the sphere by a fine stratified grid in (phi, cos theta).
  double integral = 0;
  const int n = 400;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double phi = 2 * kPi * (i + 0.5) / n, z = 1 - 2 * (j + 0.5) / n;
      const double r = std::sqrt(1 - z * z);
      integral += env.pdf({r * std::cos(phi), z, r * std::sin(phi)}) * 4 * kPi / (n * n);
    }
  EXPECT_NEAR(integral, 1.0, 2e-3);
  // Samples carry the density pdf() reports.
  eval::Rng rng(3);
  for (int k = 0; k < 1000; ++k) {
    double p = 0;
    const Vec3 d = env.sample(rng.uniform(), rng.uniform(), &p);
    EXPECT_NEAR(length(d), 1.0, 1e-12);
    EXPECT_NEAR(p, env.pdf(d), 1e-9 * p);
  }
}

TEST(Render, FootprintOfAPlaneSeenHeadOnIsThePixelSize) {
  Scene s = plane_scene(65, 65);  // odd: pixel 32 is centred on the axis
  s.objects[0].asset = assets().flat;
  s.objects[0].tiles_per_unit = 3;
  Light sun;
  sun.type = LightType::Directional;
  s.lights.push_back(sun);
  const Renderer r(s, {});
  const PixelFootprint f = r.pixel_footprint(32, 32);
  ASSERT_EQ(f.object, 0);
  // Pixel side on the plane: 2 d tan(fov / 2) / H world units, times tiles_per_unit * N texels.
  const double side = 2 * 2.0 * std::tan(15 * kPi / 180) / 65 * 3 * 16;
  EXPECT_NEAR(f.rect.x1 - f.rect.x0, side, 1e-9 * side);
  EXPECT_NEAR(f.rect.y1 - f.rect.y0, side, 1e-9 * side);
  EXPECT_NEAR(0.5 * (f.rect.x0 + f.rect.x1), 2.0 * 3 * 16, 1e-6);  // the plane's centre: u = 2
  EXPECT_NEAR(f.wo[2], 1.0, 1e-12);
}

// A 0.5-wide square seen head-on from 2 units with a 30-degree field: its edges project to
// x = W/2 (1 +- 0.25 / (2 tan 15deg)), and the pixels off silhouettes are those whose square lies
// wholly inside or wholly outside that square of the image.
TEST(Render, InteriorPixelsLeaveOutExactlyTheSilhouettes) {
  Scene s = plane_scene(32, 32);
  s.objects[0].size[0] = s.objects[0].size[1] = 0.5;
  const std::vector<uint8_t> mask = Renderer(s, {}).interior_pixels();
  ASSERT_EQ(mask.size(), 32u * 32u);
  const double lo = 16 * (1 - 0.25 / (2 * std::tan(15 * kPi / 180)));
  const double hi = 32 - lo;
  auto side = [&](int k) {  // 1 inside, -1 outside, 0 straddling the edge
    return (k >= lo && k + 1 <= hi) ? 1 : (k + 1 <= lo || k >= hi) ? -1 : 0;
  };
  int left_out = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const bool inside = side(x) == 1 && side(y) == 1;
      const bool outside = side(x) == -1 || side(y) == -1;
      EXPECT_EQ(mask[std::size_t(y) * 32 + std::size_t(x)], inside || outside ? 1 : 0)
          << x << "," << y;
      left_out += !(inside || outside);
    }
  EXPECT_EQ(left_out, 4 * (int(std::ceil(hi)) - int(std::floor(lo))) - 4);  // the ring of edges
}

// Footprint methods path trace silhouette pixels from jittered rays: the 0.5-wide Lambertian square
// of the test above under a sun, seen head-on on black, projects to the image square [lo, hi]^2, so
// a pixel's exact value is the square's radiance times the share of the pixel inside it. With
// 1 024 spp (182 x 182 stratified rays an edge pixel) the edge pixels are within 5 binomial
// standard errors of 1 024 uniform rays of it (more rays and strata only lower the error); the
// interior ones are exact; from the centre alone (jitter_edges false) an edge pixel is 0 or the
// whole value.
TEST(Render, EdgePixelsConvergeToThePixelsAreaAverage) {
  Scene s = plane_scene(32, 32);
  s.objects[0].size[0] = s.objects[0].size[1] = 0.5;
  Light sun;
  sun.type = LightType::Directional;
  sun.direction = {0, 0, -1};
  s.lights.push_back(sun);
  RenderOptions o;
  o.method = eval::Method::Reference;
  o.spp = 1024;
  const RenderResult r = Renderer(s, o).render();
  o.jitter_edges = false;
  const RenderResult centre = Renderer(s, o).render();
  const double lo = 16 * (1 - 0.25 / (2 * std::tan(15 * kPi / 180))), hi = 32 - lo;
  auto inside = [&](int k) { return std::max(0.0, std::min(k + 1.0, hi) - std::max(k + 0.0, lo)); };
  int edges = 0, centre_exact = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const double share = inside(x) * inside(y);
      const std::size_t k = 3 * (std::size_t(y) * 32 + std::size_t(x));
      for (int c = 0; c < 3; ++c) {
        const double full = s.objects[0].diffuse[c] / kPi;
        const double error = 5 * full * std::sqrt(share * (1 - share) / 1024) + 1e-6;
        EXPECT_NEAR(r.rgb[k + std::size_t(c)], full * share, error) << x << "," << y << " " << c;
      }
      if (share > 0 && share < 1) {
        ++edges;
        const double value = centre.rgb[k] / (s.objects[0].diffuse[0] / kPi);
        centre_exact += std::abs(value - share) < 0.05;
      }
    }
  EXPECT_EQ(edges, 4 * (int(std::ceil(hi)) - int(std::floor(lo))) - 4);
  EXPECT_LT(centre_exact, edges / 4);  // the centre's value is 0 or 1, rarely the share
}

// A shadow edge is left out like a silhouette: a sun at 45 degrees over -x and an occluder out of
// the camera's view (z = 1, x >= 0.6) shadow the plane for x >= -0.4, whose image is the column
// x = 16 (1 - 0.4 / (2 tan 15deg)) = 4.06: pixel column 4 straddles it.
TEST(Render, InteriorPixelsLeaveOutShadowEdges) {
  Scene s = plane_scene(32, 32);
  Object occluder = s.objects[0];
  occluder.name = "object[1]";
  occluder.center = {1.8, 0, 1};
  occluder.size[0] = 2.4;
  s.objects.push_back(occluder);
  Light sun;
  sun.type = LightType::Directional;
  sun.direction = normalize(Vec3(-1, 0, -1));
  s.lights.push_back(sun);
  const std::vector<uint8_t> mask = Renderer(s, {}).interior_pixels();
  const double edge = 16 * (1 - 0.4 / (2 * std::tan(15 * kPi / 180)));
  ASSERT_EQ(int(edge), 4);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      EXPECT_EQ(mask[std::size_t(y) * 32 + std::size_t(x)], x == 4 ? 0 : 1) << x << "," << y;
}

// plane_scene's camera and colour, square, centred on a sphere of `radius` at the origin.
Scene sphere_scene(int size, double radius) {
  Scene s = plane_scene(size, size);
  s.objects[0].shape = ShapeType::Sphere;
  s.objects[0].center = {0, 0, 0};
  s.objects[0].axis = {0, 1, 0};
  s.objects[0].radius = radius;
  return s;
}

// Where the view turns across a cloth pixel its centre's directions misstate it: a sphere of
// radius 0.5 centred in the view from 2 units, whose ray through image-plane point (a, b) (at
// tan-angle r = |(a, b)| from the axis) meets it at |cos| = sqrt(1 - (2 sin(atan r) / 0.5)^2) (a
// closed form, not the renderer's intersection). A cloth pixel is interior when its centre and
// corners all hit (or all miss) and their cosines are at least 0.7 times the largest; near the
// outline the ring of pixels whose five rays all hit, but at cosines that part, is left out. The
// same sphere in a Lambertian colour keeps that ring: it is shaded at the centre's hit whatever
// the view.
TEST(Render, InteriorPixelsLeaveOutWhereTheViewTurnsOnCloth) {
  Scene s = sphere_scene(32, 0.5);
  const std::vector<uint8_t> lambertian = Renderer(s, {}).interior_pixels();
  s.objects[0].asset = assets().twill;
  const std::vector<uint8_t> mask = Renderer(s, {}).interior_pixels();
  const double t = std::tan(15 * kPi / 180);
  // |cos| at image point (x, y), or -1 where the ray misses.
  auto cos_view = [&](double x, double y) {
    const double a = (2 * x / 32 - 1) * t, b = (1 - 2 * y / 32) * t;
    const double sin_angle = std::sqrt((a * a + b * b) / (1 + a * a + b * b));
    const double q = 1 - std::pow(2 * sin_angle / 0.5, 2);
    return q > 0 ? std::sqrt(q) : -1.0;
  };
  int turned = 0, checked = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const std::size_t k = std::size_t(y) * 32 + std::size_t(x);
      const double c[5] = {cos_view(x + 0.5, y + 0.5), cos_view(x, y), cos_view(x + 1, y),
                           cos_view(x, y + 1), cos_view(x + 1, y + 1)};
      const double least = *std::min_element(c, c + 5), most = *std::max_element(c, c + 5);
      if (least < 0 && most >= 0) {  // a silhouette
        EXPECT_EQ(mask[k], 0) << x << "," << y;
        EXPECT_EQ(lambertian[k], 0) << x << "," << y;
        continue;
      }
      EXPECT_EQ(lambertian[k], 1) << x << "," << y;  // the backdrop, or all five on the sphere
      if (most < 0) {                                // the backdrop
        EXPECT_EQ(mask[k], 1) << x << "," << y;
        continue;
      }
      if (std::abs(least - 0.7 * most) < 1e-9) continue;  // on the threshold (never, here)
      ++checked;
      turned += least < 0.7 * most;
      EXPECT_EQ(mask[k], least >= 0.7 * most ? 1 : 0)
          << x << "," << y << " cosines " << least << " .. " << most;
    }
  EXPECT_GT(turned, 60);             // the rule leaves out a ring inside the outline (104)
  EXPECT_GT(checked - turned, 400);  // and keeps the middle (584)
}

// Edge pixels converge to what path tracing does: a twill sphere under a point light, its edge
// pixels (silhouettes and the ring where the view turns) from multiscale at 2 spp (12 x 12
// stratified rays evaluated at points) against path-traced brute force at 64 spp, 8 seeds each.
// Per edge pixel p the means A_p, B_p and the variances of those means v_p (from the seeds): with
// equal expectations sum (A_p - B_p)^2 / sum (v_A,p + v_B,p) is near 1 (its numerator alone,
// a sum over the 68 edge pixels, spreads by about sqrt(2 / 68) = 0.17); it must stay under 2. The
// centre rule (jitter_edges false), biased on every silhouette pixel, must exceed 4: the test can
// tell (measured 0.85 and 34.5; rays over a quarter of each edge pixel gave 49).
TEST(Render, EdgePixelsConvergeToPathTracing) {
  Scene s = sphere_scene(16, 0.35);
  s.objects[0].asset = assets().twill;
  s.objects[0].tiles_per_unit = 4;
  Light point;
  point.position = {0.5, 0.5, 1.5};
  point.intensity = Rgb(3);
  s.lights.push_back(point);
  const Renderer renderer(s, {});
  const std::vector<uint8_t> mask = renderer.interior_pixels();
  constexpr int kSeeds = 8;
  // Per pixel, the sum and the sum of squares of its luminance over the seeds.
  struct Series {
    std::vector<double> sum = std::vector<double>(16 * 16), sum2 = std::vector<double>(16 * 16);
    void add(const RenderResult& r) {
      for (std::size_t p = 0; p < sum.size(); ++p) {
        const double l = (r.rgb[3 * p] + r.rgb[3 * p + 1] + r.rgb[3 * p + 2]) / 3;
        sum[p] += l, sum2[p] += l * l;
      }
    }
    double mean(std::size_t p) const { return sum[p] / kSeeds; }
    double variance_of_mean(std::size_t p) const {
      return std::max(0.0, sum2[p] / kSeeds - mean(p) * mean(p)) / (kSeeds - 1);
    }
  };
  Series jittered, centre, path;
  for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
    RenderOptions o;
    o.seed = seed;
    jittered.add(renderer.render(o));
    o.jitter_edges = false;
    centre.add(renderer.render(o));
    o.method = eval::Method::Brute;
    o.path_traced = true;
    o.spp = 64;
    path.add(renderer.render(o));
  }
  auto ratio = [&](const Series& a) {
    double squares = 0, variances = 0;
    for (std::size_t p = 0; p < mask.size(); ++p)
      if (mask[p] == 0) {
        squares += std::pow(a.mean(p) - path.mean(p), 2);
        variances += a.variance_of_mean(p) + path.variance_of_mean(p);
      }
    return squares / variances;
  };
  int edges = 0;
  for (uint8_t m : mask)
    edges += m == 0;
  ASSERT_GT(edges, 30);
  EXPECT_LT(ratio(jittered), 2.0);
  EXPECT_GT(ratio(centre), 4.0);
}

// The 24 x 24 plane scene with the twill at `tiles_per_unit` under a point light.
Scene lit_twill_plane(double tiles_per_unit) {
  Scene s = plane_scene(24, 24);
  s.objects[0].asset = assets().twill;
  s.objects[0].tiles_per_unit = tiles_per_unit;
  Light point;
  point.position = {0.5, 0.5, 1.5};
  point.intensity = Rgb(3);
  s.lights.push_back(point);
  return s;
}

TEST(Render, ImagesAreIdenticalForAnyThreadCount) {
  const Scene s = lit_twill_plane(0.6);  // pixels 1-2 texels wide
  RenderResult one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = Renderer(s, {}).render();
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = Renderer(s, {}).render();
  }
  ASSERT_EQ(one.rgb.size(), two.rgb.size());
  EXPECT_EQ(0, std::memcmp(one.rgb.data(), two.rgb.data(), one.rgb.size() * sizeof(float)));
  EXPECT_GT(one.stats.without_control_variate, 0u);  // the narrow footprints' branch is covered
}

// A renderer reused for another method, spp and seed renders the image a new one renders (what its
// evaluators built on earlier renders, of this method with another seed included, changes no bit),
// and refuses evaluator options of its own. Near (0.6 tiles per unit: pixels 1-2 texels wide,
// sampled without the control variate) and far (24: footprints of a tile and more, with it).
TEST(Render, AReusedRendererRendersWhatANewOneRenders) {
  for (const double tiles : {0.6, 24.0}) {
    const Scene s = lit_twill_plane(tiles);
    RenderOptions first;
    first.method = eval::Method::Brute;
    const Renderer reused(s, first);
    (void)reused.render();
    for (eval::Method m : {eval::Method::Multiscale, eval::Method::MultiscalePaper,
                           eval::Method::Brute, eval::Method::Reference}) {
      RenderOptions pass;
      pass.method = m;
      pass.spp = 1;
      pass.seed = 5;
      (void)reused.render(pass);  // as the report's warm-up
      pass.spp = 3;
      pass.seed = 11;
      const RenderResult again = reused.render(pass), fresh = Renderer(s, pass).render();
      ASSERT_EQ(again.rgb.size(), fresh.rgb.size());
      EXPECT_EQ(0,
                std::memcmp(again.rgb.data(), fresh.rgb.data(), again.rgb.size() * sizeof(float)))
          << eval::method_name(m) << " at " << tiles << " tiles per unit";
      EXPECT_EQ(again.stats.estimates, fresh.stats.estimates);
      if (m == eval::Method::Multiscale) {
        if (tiles < 2) {
          EXPECT_GT(again.stats.without_control_variate, 0u);
        } else {
          EXPECT_LT(again.stats.without_control_variate, again.stats.estimates / 10);
        }
      }
    }
    RenderOptions flat;
    flat.parallax = false;
    EXPECT_THROW((void)reused.render(flat), std::invalid_argument);
  }
}

// relMSE of an image against a reference, over pixels with a non-black reference.
double relmse(const RenderResult& a, const RenderResult& ref) {
  double sum = 0;
  int count = 0;
  for (std::size_t k = 0; k < ref.rgb.size(); ++k)
    if (ref.rgb[k] > 1e-6) {
      const double d = (a.rgb[k] - ref.rgb[k]) / ref.rgb[k];
      sum += d * d;
      ++count;
    }
  return sum / count;
}

TEST(Render, MultiscaleAndBruteForceConvergeAtTheMonteCarloRate) {
  Scene s = plane_scene(24, 24);
  s.objects[0].asset = assets().twill;
  s.objects[0].tiles_per_unit = 32;  // far field: footprints of a tile (64 texels) and more
  Light point;
  point.position = {0.4, 0.6, 1.6};
  point.intensity = Rgb(3);
  s.lights.push_back(point);
  RenderOptions ro;
  ro.method = eval::Method::Reference;
  // One renderer for every pass (its assets opened once, as a renderer keeps them between frames:
  // the images are those of new renderers, Render.AReusedRendererRendersWhatANewOneRenders).
  const Renderer renderer(s, ro);
  const RenderResult ref = renderer.render();
  for (eval::Method m : {eval::Method::Multiscale, eval::Method::Brute}) {
    std::vector<double> x, y;
    for (uint32_t spp : {1u, 4u, 16u, 64u}) {
      // The mean over 4 seeds of relMSE, so that the slope is not one image's luck.
      double e = 0;
      for (uint64_t seed = 1; seed <= 4; ++seed) {
        RenderOptions o;
        o.method = m;
        o.spp = spp;
        o.seed = seed;
        const RenderResult image = renderer.render(o);
        e += relmse(image, ref) / 4;
        // The control variate is what this tests: these far-field footprints keep it.
        if (m == eval::Method::Multiscale) {
          EXPECT_LT(image.stats.without_control_variate, image.stats.estimates / 10);
        }
      }
      x.push_back(std::log(double(spp)));
      y.push_back(std::log(e));
    }
    // Least-squares slope of log relMSE against log spp: -1 for an unbiased Monte Carlo estimator,
    // steeper where the footprint's stratification (eval/footprint_samples.hpp) pays: brute force
    // on a piecewise-constant texture measured -1.28, the control-variate residual -1.08. A bias
    // floor would flatten it towards 0.
    double mx = 0, my = 0;
    for (std::size_t k = 0; k < x.size(); ++k)
      mx += x[k] / x.size(), my += y[k] / y.size();
    double sxy = 0, sxx = 0;
    for (std::size_t k = 0; k < x.size(); ++k)
      sxy += (x[k] - mx) * (y[k] - my), sxx += (x[k] - mx) * (x[k] - mx);
    const double slope = sxy / sxx;
    std::printf("%s: relMSE slope %.3f (1 spp %.3g, 64 spp %.3g)\n", eval::method_name(m), slope,
                std::exp(y.front()), std::exp(y.back()));
    EXPECT_LT(slope, -0.85) << eval::method_name(m);
    EXPECT_GT(slope, -1.6) << eval::method_name(m);
    // No bias floor: the last step still falls by about its factor of 4.
    EXPECT_LT(y[3] - y[2], std::log(0.4)) << eval::method_name(m);
  }
}

}  // namespace
// Negative pixels: a pixel counts once whichever channels are below 0, the least channel is
// reported, -0 and 0 are not negative; a render reports its image's own count, and the exact
// reference (a sum of non-negative terms) has none. (The fixture's multi-scale renders here have
// no negative pixel, so the counting is checked on a made image.)
TEST(Render, CountsNegativePixelsAndTheirLeastValue) {
  const std::vector<float> rgb = {0.5f,  0.2f, 0.1f,  -0.0f, 0.0f, 1.0f, -0.25f, 0.3f,
                                  -0.5f, 0.1f, -0.1f, 0.2f,  0.0f, 0.0f, 0.0f};
  const NegativePixels n = count_negative_pixels(rgb);
  EXPECT_EQ(n.count, 2u);
  EXPECT_EQ(n.least, -0.5);
  EXPECT_EQ(count_negative_pixels({0.1f, 0.2f, 0.3f}).count, 0u);
  EXPECT_EQ(count_negative_pixels({0.1f, 0.2f, 0.3f}).least, 0.0);
  RenderOptions o;
  o.method = eval::Method::Reference;
  const Scene s = lit_twill_plane(24.0);
  const RenderResult r = Renderer(s, o).render();
  const NegativePixels own = count_negative_pixels(r.rgb);
  EXPECT_EQ(r.stats.negative_pixels, own.count);
  EXPECT_EQ(r.stats.min_value, own.least);
  EXPECT_EQ(r.stats.negative_pixels, 0u);
}

}  // namespace clothbake::render

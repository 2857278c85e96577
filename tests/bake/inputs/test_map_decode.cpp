// Map decoding: the same data stored as 8/16-bit PNG/TIFF and half/float EXR/TIFF decodes to the
// same values within quantisation; normals from heights match the closed form; statistics.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "bake/inputs/map_image.hpp"
#include "bake/inputs/map_normals.hpp"
#include "bake/inputs/map_stats.hpp"
#include "tests/bake/inputs/test_support.hpp"

namespace clothbake::inputs {
namespace {

using clothbake::testing::error_message;
using clothbake::testing::make_image;
using clothbake::testing::ScratchDir;
using ::testing::HasSubstr;

constexpr int kN = 16;

double ref_height(int x, int y) {
  return 0.5 + 0.4 * std::sin(2 * M_PI * x / kN) * std::cos(2 * M_PI * y / kN);
}
double ref_gap(int x, int y) {
  return (x + y) % 5 == 0 ? 0.0 : 1.0;
}
int ref_id(int x, int y) {
  return (x / 4 + y / 4) % 4;
}
Vec3f ref_vector(int x, int y) {
  // Unit vectors spread over the upper hemisphere (z > 0.2 so that they are also valid normals).
  double phi = 2 * M_PI * (x + 0.37 * y) / kN, z = 0.25 + 0.7 * y / (kN - 1.0);
  double r = std::sqrt(1 - z * z);
  return {float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
}
double ref_albedo(int x, int y, int c) {
  return (x * 3 + y * 5 + c * 7) % 17 / 16.0;
}

struct Format {
  const char* ext;
  PixelType type;
  double scalar_tolerance;  // absolute, for values in [0, 1]
  double vector_tolerance;  // per component after normalisation
};

class FormatAgreement : public ::testing::TestWithParam<Format> {};

TEST_P(FormatAgreement, DecodesToTheSameMapsWithinQuantisation) {
  const Format fmt = GetParam();
  ScratchDir dir;
  bool integer = fmt.type == PixelType::UInt8 || fmt.type == PixelType::UInt16;
  double id_scale = fmt.type == PixelType::UInt8    ? 255.0
                    : fmt.type == PixelType::UInt16 ? 65535.0
                                                    : 1.0;
  auto path = [&](const char* role) { return dir / (std::string(role) + "." + fmt.ext); };
  write_image(path("height"),
              make_image(kN, kN, 1, [](int x, int y, int) { return ref_height(x, y); }), fmt.type);
  write_image(path("gap"), make_image(kN, kN, 1, [](int x, int y, int) { return ref_gap(x, y); }),
              fmt.type);
  write_image(path("yarn_id"),
              make_image(kN, kN, 1, [&](int x, int y, int) { return ref_id(x, y) / id_scale; }),
              fmt.type);
  auto encode = [&](int x, int y, int c) {
    double v = ref_vector(x, y)[c];
    return integer ? 0.5 * v + 0.5 : v;
  };
  write_image(path("tangent"), make_image(kN, kN, 3, encode), fmt.type);
  write_image(
      path("normal"),
      make_image(kN, kN, 4, [&](int x, int y, int c) { return c == 3 ? 1.0 : encode(x, y, c); }),
      fmt.type);  // RGBA: alpha ignored
  write_image(path("albedo"), make_image(kN, kN, 3, ref_albedo), fmt.type);

  auto read = [&](const char* role) {
    return read_map_image(path(role), role, std::string("test ") + role);
  };
  MapImage height_image = read("height");
  EXPECT_EQ(height_image.integer_encoded, integer);
  auto height = decode_height(height_image, 1.0);
  auto gap = decode_gap(read("gap"));
  auto ids = decode_yarn_ids(read("yarn_id"));
  auto tangents = decode_tangents(read("tangent"));
  auto normals = decode_normals(read("normal"));
  auto albedo = decode_albedo(read("albedo"), false);
  for (int y = 0; y < kN; ++y)
    for (int x = 0; x < kN; ++x) {
      std::size_t i = std::size_t(y) * kN + x;
      ASSERT_NEAR(height[i], ref_height(x, y), fmt.scalar_tolerance) << x << "," << y;
      ASSERT_NEAR(gap[i], ref_gap(x, y), fmt.scalar_tolerance);
      ASSERT_EQ(ids[i], ref_id(x, y)) << "yarn ids must be exact in every format";
      Vec3f r = ref_vector(x, y);
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(tangents[i][c], r[c], fmt.vector_tolerance) << x << "," << y << " c" << c;
        ASSERT_NEAR(normals[i][c], r[c], fmt.vector_tolerance);
        ASSERT_NEAR(albedo[i][c], ref_albedo(x, y, c), fmt.scalar_tolerance);
      }
      double len = std::sqrt(double(tangents[i][0]) * tangents[i][0] +
                             double(tangents[i][1]) * tangents[i][1] +
                             double(tangents[i][2]) * tangents[i][2]);
      ASSERT_NEAR(len, 1.0, 1e-6) << "decoded tangents are unit";
    }
}

// 8-bit: half a step of 1/255 for scalars; vectors are quantised per component (2/255 before
// normalisation, which can move a component by about twice that).
INSTANTIATE_TEST_SUITE_P(
    Formats, FormatAgreement,
    ::testing::Values(Format{"png", PixelType::UInt8, 0.5 / 255 + 1e-6, 4.5 / 255},
                      Format{"png", PixelType::UInt16, 0.5 / 65535 + 1e-6, 4.5 / 65535},
                      Format{"tif", PixelType::UInt8, 0.5 / 255 + 1e-6, 4.5 / 255},
                      Format{"tif", PixelType::UInt16, 0.5 / 65535 + 1e-6, 4.5 / 65535},
                      Format{"tif", PixelType::Float32, 1e-7, 1e-6},
                      Format{"exr", PixelType::Half, 1e-3, 2e-3},
                      Format{"exr", PixelType::Float32, 1e-7, 1e-6}),
    [](const auto& info) {
      const char* t = info.param.type == PixelType::UInt8    ? "u8"
                      : info.param.type == PixelType::UInt16 ? "u16"
                      : info.param.type == PixelType::Half   ? "half"
                                                             : "float";
      return std::string(info.param.ext) + "_" + t;
    });

TEST(MapDecode, GreyAlbedoIsReplicatedAndSrgbIsDecoded) {
  ScratchDir dir;
  write_image(dir / "a.png", make_image(4, 4, 1, [](int x, int, int) { return x / 3.0; }),
              PixelType::UInt8);
  auto grey = decode_albedo(read_map_image(dir / "a.png", "albedo", "t"), false);
  auto srgb = decode_albedo(read_map_image(dir / "a.png", "albedo", "t"), true);
  for (int x = 0; x < 4; ++x) {
    EXPECT_EQ(grey[x][0], grey[x][1]);
    EXPECT_EQ(grey[x][1], grey[x][2]);
    EXPECT_NEAR(srgb[x][0], srgb_to_linear(grey[x][0]), 1e-7);
  }
  EXPECT_NEAR(srgb[1][0], 0.0908417, 2e-3);  // 85/255 in sRGB is ~0.0908 linear
}

TEST(MapDecode, SrgbTransferFunctionRoundTrips) {
  for (double v = 0; v <= 1.0; v += 0.01)
    EXPECT_NEAR(linear_to_srgb(srgb_to_linear(v)), v, 1e-12);
  EXPECT_DOUBLE_EQ(srgb_to_linear(1.0), 1.0);
  EXPECT_DOUBLE_EQ(srgb_to_linear(0.0), 0.0);
}

TEST(MapDecode, ChannelRules) {
  ScratchDir dir;
  write_image(dir / "rgb.exr", make_image(4, 4, 3, [](int, int, int) { return 0.5; }),
              PixelType::Float32);
  write_image(dir / "ga.png", make_image(4, 4, 2, [](int, int, int) { return 0.5; }),
              PixelType::UInt8);
  EXPECT_THAT(error_message([&] { read_map_image(dir / "rgb.exr", "height", "ctx"); }),
              HasSubstr("ctx: " + dir / "rgb.exr" +
                        ": image has 3 channels; a height map needs 1 channel"));
  EXPECT_THAT(error_message([&] { read_map_image(dir / "ga.png", "albedo", "ctx"); }),
              HasSubstr("has 2 channels"));
  EXPECT_THAT(error_message([&] { read_map_image(dir / "ga.png", "tangent", "ctx"); }),
              HasSubstr("a tangent map needs 3 channels"));
  EXPECT_NO_THROW(read_map_image(dir / "rgb.exr", "albedo", "ctx"));
}

TEST(MapDecode, FloatYarnIdsMustBeIntegers) {
  ScratchDir dir;
  write_image(dir / "id.exr",
              make_image(4, 4, 1, [](int x, int y, int) { return x == 2 && y == 1 ? 1.5 : 1.0; }),
              PixelType::Float32);
  std::string msg =
      error_message([&] { decode_yarn_ids(read_map_image(dir / "id.exr", "yarn_id", "ctx")); });
  EXPECT_THAT(msg, HasSubstr("pixel (2, 1) has yarn id 1.5, which is not an integer"));
  write_image(dir / "neg.exr",
              make_image(4, 4, 1, [](int x, int, int) { return x == 3 ? -1.0 : 0.0; }),
              PixelType::Float32);
  EXPECT_THAT(
      error_message([&] { decode_yarn_ids(read_map_image(dir / "neg.exr", "yarn_id", "ctx")); }),
      HasSubstr("pixel (3, 0) has yarn id -1, outside [0, 65535]"));
}

TEST(MapDecode, OutOfRangeGapAndAlbedoNameThePixel) {
  ScratchDir dir;
  write_image(dir / "g.exr",
              make_image(4, 4, 1, [](int x, int y, int) { return x == 1 && y == 3 ? 1.2 : 1.0; }),
              PixelType::Float32);
  EXPECT_THAT(error_message([&] { decode_gap(read_map_image(dir / "g.exr", "gap", "ctx")); }),
              HasSubstr("pixel (1, 3) has gap value 1.2, outside [0, 1]"));
  write_image(dir / "a.exr",
              make_image(4, 4, 3, [](int x, int, int c) { return x == 0 && c == 2 ? -0.1 : 0.5; }),
              PixelType::Float32);
  EXPECT_THAT(
      error_message([&] { decode_albedo(read_map_image(dir / "a.exr", "albedo", "ctx"), false); }),
      HasSubstr("pixel (0, 0) channel 2 has albedo -0.1"));
}

TEST(MapDecode, DownwardNormalIsRejected) {
  ScratchDir dir;
  write_image(dir / "n.exr",
              make_image(4, 4, 3,
                         [](int x, int y, int c) {
                           double v[3] = {0, 0, x == 3 && y == 2 ? -1.0 : 1.0};
                           return v[c];
                         }),
              PixelType::Float32);
  EXPECT_THAT(
      error_message([&] { decode_normals(read_map_image(dir / "n.exr", "normal", "ctx")); }),
      HasSubstr("pixel (3, 2) has a normal (0, 0, -1) that does not point up"));
}

TEST(NormalsFromHeight, MatchesTheDiscreteClosedFormOfASinusoid) {
  // h = A sin(2 pi u): the wrapped central difference is exactly A N sin(2 pi / N) cos(2 pi u).
  const int n = 32;
  const double a = 0.05;
  std::vector<float> h(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      h[std::size_t(y) * n + x] = float(a * std::sin(2 * M_PI * x / n));
  auto normals = normals_from_height(h, n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double du = a * n * std::sin(2 * M_PI / n) * std::cos(2 * M_PI * x / n);
      double len = std::sqrt(du * du + 1);
      const Vec3f& nr = normals[std::size_t(y) * n + x];
      EXPECT_NEAR(nr[0], -du / len, 2e-6);
      EXPECT_NEAR(nr[1], 0.0, 1e-7);
      EXPECT_NEAR(nr[2], 1 / len, 2e-6);
    }
  // And it converges to the analytic gradient 2 pi A cos(2 pi u) as N grows.
  double analytic = 2 * M_PI * a, discrete = a * n * std::sin(2 * M_PI / n);
  EXPECT_NEAR(discrete / analytic, 1.0, 0.01);
}

TEST(NormalsFromHeight, VGradientUsesRowsDownwards) {
  // h increases with y (rows go down the image = +v): the normal tilts towards -y.
  const int n = 8;
  std::vector<float> h(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      h[std::size_t(y) * n + x] = float(0.01 * std::sin(2 * M_PI * y / n));
  auto normals = normals_from_height(h, n);
  EXPECT_LT(normals[std::size_t(0) * n + 3][1], 0.f);  // dh/dv > 0 at y = 0
  EXPECT_NEAR(normals[std::size_t(0) * n + 3][0], 0.f, 1e-7);
}

TEST(MapStats, ChannelStatsOfAKnownSet) {
  ChannelStats s = channel_stats(std::vector<float>{2, 4, 4, 4, 5, 5, 7, 9});
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_DOUBLE_EQ(s.stddev, 2.0);  // population standard deviation of the classic example
  EXPECT_DOUBLE_EQ(s.min, 2.0);
  EXPECT_DOUBLE_EQ(s.max, 9.0);
}

TEST(MapStats, TangentStatisticsAreAxial) {
  // Half the fibres along +x, half along -x: the same line, so concentration 1, axis 0 deg.
  std::vector<Vec3f> t = {{1, 0, 0}, {-1, 0, 0}, {1, 0, 0}, {-1, 0, 0}};
  TangentStats s = tangent_stats(t);
  EXPECT_NEAR(s.axial_concentration, 1.0, 1e-12);
  EXPECT_NEAR(s.mean_axis_deg, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.fraction_along_x, 1.0);
  // x and y in equal numbers cancel: concentration 0.
  s = tangent_stats({{1, 0, 0}, {0, 1, 0}});
  EXPECT_NEAR(s.axial_concentration, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.fraction_along_x, 0.5);
  EXPECT_DOUBLE_EQ(s.fraction_along_y, 0.5);
  // Lines at +45 and at -135 degrees (the same line): axis 45.
  float r = float(std::sqrt(0.5));
  s = tangent_stats({{r, r, 0}, {-r, -r, 0}});
  EXPECT_NEAR(s.mean_axis_deg, 45.0, 1e-4);
  // Elevation: a fibre at 30 degrees out of the plane.
  s = tangent_stats({{float(std::cos(M_PI / 6)), 0, 0.5f}});
  EXPECT_NEAR(s.mean_elevation_deg, 30.0, 1e-4);
  EXPECT_NEAR(s.mean_abs_z, 0.5, 1e-7);
}

TEST(MapStats, GapFractionAndYarnCounts) {
  FabricMaps m;
  m.resolution = 2;
  m.height = {0, 0, 0, 0};
  m.gap = {1, 0, 0.4f, 0.6f};
  m.yarn_id = {0, 2, 2, 0};
  m.tangent = m.normal = m.albedo = std::vector<Vec3f>(4, Vec3f{0, 0, 1});
  MapStats s = map_stats(m);
  EXPECT_DOUBLE_EQ(s.gap_fraction, 0.5);
  ASSERT_EQ(s.yarn_texels.size(), 3u);
  EXPECT_EQ(s.yarn_texels[0], 2u);
  EXPECT_EQ(s.yarn_texels[1], 0u);
  EXPECT_EQ(s.yarn_texels[2], 2u);
  EXPECT_NEAR(s.mean_normal_tilt_deg, 0.0, 1e-9);
}

}  // namespace
}  // namespace clothbake::inputs

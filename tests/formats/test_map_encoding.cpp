// The 16-bit codes of the feature maps (formats/reader/map_encoding.hpp, formats/writer/
// map_encoding.hpp), stored entropy-coded (compress/map_entropy.hpp): the error bound of every
// encoding against the f32 value, the reader's decoding of the stored maps against the fabric's,
// and hostile payloads (the retired plain forms, wrong shapes and versions, NaN f16 heights, codes
// that decode to a normal below the horizon) reported with their stable check IDs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "common/error.hpp"
#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/map_encoding.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"
#include "formats/writer/half_float.hpp"
#include "formats/writer/map_encoding.hpp"
#include "tests/formats/test_fabric.hpp"
#include "tests/support/fabric_asset_sections.hpp"

namespace {

using namespace clothbake;
using formats::Section;
using reader::SectionType;

// The bounds this test asserts (and docs/format.md §6.4 states).
constexpr double kUnormBound = 1.0 / 131070 + 6e-8;  // half a step plus the float division
constexpr double kOctahedralBoundRad = 5.0e-5;

double angle(const float a[3], const double b[3]) {
  // atan2 of |a x b| and a.b: accurate for tiny angles, unlike acos.
  const double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2],
               cz = a[0] * b[1] - a[1] * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz),
                    (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]));
}

double round_trip_angle(const double v[3]) {
  const float f[3] = {float(v[0]), float(v[1]), float(v[2])};
  int16_t code[2];
  formats::unit_to_octahedral(f, code);
  float d[3];
  reader::decode_octahedral(code, d);
  return angle(d, v);
}

TEST(MapEncoding, Unorm16WithinHalfAStepAndExactAtTheEnds) {
  EXPECT_EQ(reader::unorm16_to_float(formats::float_to_unorm16(0.f)), 0.f);
  EXPECT_EQ(reader::unorm16_to_float(formats::float_to_unorm16(1.f)), 1.f);
  EXPECT_EQ(formats::float_to_unorm16(-0.5f), 0);    // clamped
  EXPECT_EQ(formats::float_to_unorm16(7.f), 65535);  // clamped
  EXPECT_EQ(formats::float_to_unorm16(NAN), 0);      // callers refuse NaN; no UB here
  double worst = 0.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 200000; ++i) {
    const float x = i < 65536 ? (float(i) + 0.5f) / 65536.f : u(rng);
    worst = std::max(worst,
                     std::fabs(double(reader::unorm16_to_float(formats::float_to_unorm16(x))) - x));
  }
  EXPECT_LE(worst, kUnormBound);
  EXPECT_GT(worst, 0.9 / 131070);  // the bound is tight: the test would see a coarser encoding
}

TEST(MapEncoding, HalfHeightWithinTheRelativeBound) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  double worst_rel = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const float h = u(rng);
    const float back = reader::half_to_float(formats::float_to_half(h));
    const double err = std::fabs(double(back) - h);
    if (std::fabs(h) >= std::ldexp(1.0, -14))
      worst_rel = std::max(worst_rel, err / std::fabs(h));
    else
      EXPECT_LE(err, std::ldexp(1.0, -25));
  }
  EXPECT_LE(worst_rel, std::ldexp(1.0, -11));
  EXPECT_GT(worst_rel, std::ldexp(1.0, -12));
}

TEST(MapEncoding, OctahedralWithinTheAngleBoundAndExactOnTheAxes) {
  const double axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& a : axes) {
    const float f[3] = {float(a[0]), float(a[1]), float(a[2])};
    int16_t code[2];
    formats::unit_to_octahedral(f, code);
    float d[3];
    reader::decode_octahedral(code, d);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(d[c], f[c]) << a[0] << " " << a[1] << " " << a[2];
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  double worst = 0.0;
  for (int i = 0; i < 300000; ++i) {
    double v[3] = {g(rng), g(rng), g(rng)};
    if (i % 3 == 0) v[2] = std::fabs(v[2]) * 1e-3;  // near the horizon, where the folds meet
    worst = std::max(worst, round_trip_angle(v));
  }
  EXPECT_LE(worst, kOctahedralBoundRad);
  EXPECT_GT(worst, 1e-5);  // 16-bit codes, not a float copy
  const float zero[3] = {0.f, 0.f, 0.f};
  int16_t code[2];
  formats::unit_to_octahedral(zero, code);
  EXPECT_EQ(code[0], 0);
  EXPECT_EQ(code[1], 0);
}

TEST(MapEncoding, EveryOctahedralCodeDecodesToAUnitVector) {
  // Any bytes are a valid texel: a sweep over the code square, its edges and -32768.
  for (int a = -32768; a <= 32767; a += 97)
    for (int b : {-32768, -32767, -1, 0, 1, 12345, 32766, 32767, a}) {
      const int16_t code[2] = {int16_t(a), int16_t(b)};
      float d[3];
      reader::decode_octahedral(code, d);
      const double len = std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]);
      ASSERT_NEAR(len, 1.0, 1e-6) << a << " " << b;
    }
}

// A fabric whose maps are not codes: random unit tangents and normals (z > 0), heights and
// colours, so that every encoding rounds.
Fabric noisy_fabric(int n) {
  Fabric f = test_support::make_test_fabric(n);
  std::mt19937 rng(5);
  std::normal_distribution<float> g;
  std::uniform_real_distribution<float> u(0.f, 1.f);
  auto unit = [&](bool upper) {
    Vec3f v{g(rng), g(rng), g(rng)};
    if (upper) v[2] = std::fabs(v[2]) + 0.05f;
    const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return Vec3f{v[0] / l, v[1] / l, v[2] / l};
  };
  for (std::size_t t = 0; t < f.maps.texel_count(); ++t) {
    f.maps.height[t] = 0.1f * u(rng) - 0.02f;
    f.maps.tangent[t] = unit(false);
    f.maps.normal[t] = unit(true);
    f.maps.gap[t] = t % 5 == 0 ? 1.f : u(rng);
    f.maps.albedo[t] = {u(rng), u(rng), u(rng)};
  }
  return f;
}

std::vector<Section> asset_sections(const Fabric& fabric) {
  auto s = test_support::fabric_asset_sections(fabric);
  s.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  return s;
}

struct Opened {
  std::vector<uint64_t> words;
  reader::Asset asset;
  reader::Status status;
  explicit Opened(const std::vector<std::byte>& bytes) : words((bytes.size() + 7) / 8) {
    std::memcpy(words.data(), bytes.data(), bytes.size());
    status = asset.open_memory(words.data(), bytes.size());
  }
};

struct Findings {
  std::vector<std::string> ids, messages;
  bool has(const std::string& id) const {
    return std::find(ids.begin(), ids.end(), id) != ids.end();
  }
};

Findings validate(const reader::Asset& asset) {
  Findings f;
  reader::validate_asset(
      asset,
      [](void* user, reader::Check check, uint32_t, const char* message) {
        auto* findings = static_cast<Findings*>(user);
        findings->ids.push_back(reader::check_id(check));
        findings->messages.push_back(message);
      },
      &f);
  return f;
}

TEST(MapEncoding, StoredMapsReadBackWithinTheBoundsOfTheF32Maps) {
  const Fabric fabric = noisy_fabric(32);
  Opened packed(formats::serialize_asset(asset_sections(fabric)));
  ASSERT_TRUE(packed.status.ok()) << packed.status.message();
  EXPECT_EQ(packed.asset.version_major(), 2);
  EXPECT_EQ(packed.asset.version_minor(), 0);
  reader::FeatureMaps maps;
  ASSERT_TRUE(reader::read_feature_maps(packed.asset, &maps).ok());
  ASSERT_EQ(maps.resolution, 32u);
  ASSERT_EQ(maps.tangent.size, 32u * 32u * 3u);
  ASSERT_EQ(maps.tangent.rank, 3);
  ASSERT_EQ(maps.tangent.dims[2], 3u);
  double worst_tangent = 0, worst_normal = 0, worst_unorm = 0, worst_height_rel = 0;
  for (std::size_t t = 0; t < fabric.maps.texel_count(); ++t) {
    worst_height_rel =
        std::max(worst_height_rel, std::fabs(double(maps.height[t]) - fabric.maps.height[t]) /
                                       std::fabs(fabric.maps.height[t]));
    worst_unorm = std::max(worst_unorm, std::fabs(double(maps.gap[t]) - fabric.maps.gap[t]));
    for (int c = 0; c < 3; ++c)
      worst_unorm = std::max(worst_unorm,
                             std::fabs(double(maps.albedo[3 * t + c]) - fabric.maps.albedo[t][c]));
    const double tv[3] = {fabric.maps.tangent[t][0], fabric.maps.tangent[t][1],
                          fabric.maps.tangent[t][2]};
    const double nv[3] = {fabric.maps.normal[t][0], fabric.maps.normal[t][1],
                          fabric.maps.normal[t][2]};
    worst_tangent = std::max(worst_tangent, angle(maps.tangent.data + 3 * t, tv));
    worst_normal = std::max(worst_normal, angle(maps.normal.data + 3 * t, nv));
    ASSERT_EQ(maps.yarn_id[t], fabric.maps.yarn_id[t]);
    if (t % 5 == 0) {
      ASSERT_EQ(maps.gap[t], 1.f);  // 1 = yarn stays exact
    }
  }
  EXPECT_LE(worst_height_rel, std::ldexp(1.0, -11));
  EXPECT_LE(worst_unorm, kUnormBound);
  EXPECT_LE(worst_tangent, kOctahedralBoundRad);
  EXPECT_LE(worst_normal, kOctahedralBoundRad);
  EXPECT_GT(worst_unorm, 0.0);  // really packed
  const Findings f = validate(packed.asset);
  EXPECT_TRUE(f.ids.empty()) << (f.messages.empty() ? "" : f.messages[0]);
  // Moving keeps the views valid (the decoded storage is on the heap).
  const float* tangent = maps.tangent.data;
  reader::FeatureMaps moved = std::move(maps);
  EXPECT_EQ(moved.tangent.data, tangent);
}

TEST(MapEncoding, CodesAreAboutHalfTheSizeOfFloats) {
  // The code arrays before entropy coding: 20 bytes a texel against the 46 of f32 maps.
  const Fabric fabric = test_support::make_test_fabric(64);
  uint64_t packed = 0;
  for (const auto& s : feature_map_codes(fabric.maps))
    packed += s.payload.size();
  EXPECT_EQ(packed, 64u * 64u * 20u);  // 2 + 4 + 4 + 2 + 2 + 6
}

// Replaces the section of `type` in `sections` by `replacement`.
void replace(std::vector<Section>& sections, SectionType type, Section replacement) {
  for (auto& s : sections)
    if (s.type == type) s = std::move(replacement);
}

// The coded section of a code array (as feature_map_codes makes them) of 8 x 8 texels.
template <class T>
Section coded(SectionType type, const std::vector<T>& codes, std::vector<uint32_t> dims) {
  return compress::entropy_code_map(formats::make_array_section<T>(type, 0, codes, dims));
}

// read_feature_maps refuses `sections` with `id` and validate reports it.
void expect_refused(const std::vector<Section>& sections, const char* id, const char* map) {
  Opened opened(formats::serialize_asset(sections));
  ASSERT_TRUE(opened.status.ok());
  reader::FeatureMaps maps;
  const reader::Status s = reader::read_feature_maps(opened.asset, &maps);
  EXPECT_STREQ(s.check_id(), id) << s.message();
  EXPECT_NE(std::string(s.message()).find(map), std::string::npos) << s.message();
  EXPECT_EQ(maps.resolution, 0u);  // *out unchanged on error
  EXPECT_TRUE(validate(opened.asset).has(id));
}

TEST(MapEncoding, RetiredFormsWrongShapesAndVersionsAreRefused_E015_E016) {
  const Fabric fabric = test_support::make_test_fabric(8);
  // The f32 map of format 1 and the plain 16-bit codes of format 1.4: not a 2.0 form.
  {
    auto sections = asset_sections(fabric);
    replace(
        sections, SectionType::HeightMap,
        formats::make_array_section<float>(SectionType::HeightMap, 0, fabric.maps.height, {8, 8}));
    expect_refused(sections, "CBK-E015", "height");
  }
  {
    auto sections = asset_sections(fabric);
    std::vector<uint16_t> gap(64, 65535);
    replace(sections, SectionType::GapMap,
            formats::make_array_section<uint16_t>(SectionType::GapMap, 0, gap, {8, 8}));
    expect_refused(sections, "CBK-E015", "gap");
  }
  // Octahedral tangents with three codes per texel: six byte planes where four belong.
  {
    auto sections = asset_sections(fabric);
    replace(sections, SectionType::TangentMap,
            coded(SectionType::TangentMap, std::vector<int16_t>(8 * 8 * 3, 0), {8, 8, 3}));
    expect_refused(sections, "CBK-E015", "tangent");
  }
  // A payload version this reader does not know.
  {
    auto sections = asset_sections(fabric);
    for (auto& s : sections)
      if (s.type == SectionType::GapMap) s.version = 2;
    Opened opened(formats::serialize_asset(sections));
    ASSERT_TRUE(opened.status.ok());
    reader::FeatureMaps maps;
    const reader::Status s = reader::read_feature_maps(opened.asset, &maps);
    EXPECT_EQ(s.code(), reader::ErrorCode::Unsupported) << s.message();
    EXPECT_EQ(maps.resolution, 0u);
  }
  // A coded map of another size than the rest.
  {
    auto sections = asset_sections(fabric);
    replace(sections, SectionType::GapMap,
            coded(SectionType::GapMap, std::vector<uint16_t>(4 * 4, 65535), {4, 4}));
    expect_refused(sections, "CBK-E016", "gap");
  }
}

TEST(MapEncoding, HostileCodesAreReported_E017_E021) {
  const Fabric fabric = test_support::make_test_fabric(8);
  {
    // A NaN and an Inf f16 height (a foreign writer's: clothbake's refuses them).
    auto sections = asset_sections(fabric);
    std::vector<reader::Half> height(64, formats::float_to_half(0.25f));
    height[9].bits = 0x7e00;   // NaN
    height[10].bits = 0xfc00;  // -Inf
    Section h;                 // by hand: make_array_section refuses NaN and Inf
    h.type = SectionType::HeightMap;
    h.element = reader::ElementType::F16;
    h.dims = {8, 8};
    h.payload.resize(128);
    std::memcpy(h.payload.data(), height.data(), 128);
    replace(sections, SectionType::HeightMap, compress::entropy_code_map(h));
    Opened opened(formats::serialize_asset(sections));
    ASSERT_TRUE(opened.status.ok());
    reader::FeatureMaps maps;
    ASSERT_TRUE(reader::read_feature_maps(opened.asset, &maps).ok());  // coding and shapes only
    EXPECT_TRUE(std::isnan(maps.height[9]));
    const Findings f = validate(opened.asset);
    ASSERT_TRUE(f.has("CBK-E017"));
    bool named = false;
    for (const auto& m : f.messages)
      named = named ||
              m.find("height map: 2 NaN or Inf texels (first at x=1, y=1)") != std::string::npos;
    EXPECT_TRUE(named);
  }
  {
    // Normal codes that decode below the horizon: (1, 1) is the folded corner, (0, 0, -1).
    auto sections = asset_sections(fabric);
    std::vector<int16_t> normal(64 * 2, 0);
    normal[2 * 5] = 32767;
    normal[2 * 5 + 1] = 32767;
    replace(sections, SectionType::NormalMap, coded(SectionType::NormalMap, normal, {8, 8, 2}));
    Opened opened(formats::serialize_asset(sections));
    ASSERT_TRUE(opened.status.ok());
    reader::FeatureMaps maps;
    ASSERT_TRUE(reader::read_feature_maps(opened.asset, &maps).ok());
    EXPECT_EQ(maps.normal[3 * 5 + 2], -1.f);
    const Findings f = validate(opened.asset);
    ASSERT_TRUE(f.has("CBK-E021"));
    bool named = false;
    for (const auto& m : f.messages)
      named = named ||
              m.find("normal map: 1 texels have z <= 0 (first at x=5, y=0)") != std::string::npos;
    EXPECT_TRUE(named);
    EXPECT_FALSE(f.has("CBK-W004"));  // every code decodes to a unit vector
  }
}

TEST(MapEncoding, WriterRefusesWhatTheCodesCannotHold) {
  Fabric fabric = test_support::make_test_fabric(8);
  fabric.maps.tangent[8 * 2 + 3][1] = NAN;
  try {
    (void)feature_map_codes(fabric.maps);
    FAIL() << "NaN tangent accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tangent element 58 [2, 3, 1] is NaN"), std::string::npos)
        << e.what();
  }
  fabric = test_support::make_test_fabric(8);
  fabric.maps.height[4] = 1e6f;
  try {
    (void)feature_map_codes(fabric.maps);
    FAIL() << "height beyond f16 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("f16 range"), std::string::npos) << e.what();
  }
}

}  // namespace

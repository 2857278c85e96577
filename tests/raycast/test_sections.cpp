// The ray-casting sections through the writer and the reader library
// (formats/reader/parallax_sections.hpp, visibility_sections.hpp): round trips, per-texel and
// footprint queries against brute force (fractional, negative and multi-tile rectangles, the far
// corner of a 256^2 table, a 512^2 table whose sums exceed 2^32), hostile sections, and the two
// pipeline stages end to end.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "raycast/raycast_sections.hpp"
#include "tests/raycast/synthetic_fields.hpp"
#include "tests/support/memory_asset.hpp"

using namespace clothbake;
using namespace clothbake::raycast;
using model::Vec3d;
using reader::ErrorCode;

namespace {

using test_support::MemoryAsset;
using test_support::with_metadata;

// A table of pseudo-random codes (no ray casting): for the SAT and query tests.
ParallaxTable random_table(int n, int dirs, uint64_t seed, uint16_t max_code = 65535) {
  ParallaxTable t;
  t.resolution = n;
  t.dirs = dirs;
  t.min_cos = 0.6;
  t.reference_height = 0.3;
  t.depth_scale = 0.25 / 65535.0;
  t.depth.resize(std::size_t(dirs) * dirs * n * n);
  std::mt19937_64 rng(seed);
  for (auto& c : t.depth)
    c = uint16_t(rng() % (uint64_t(max_code) + 1));
  return t;
}

// Brute-force mean of r over [x0, x1) x [y0, y1) (texel units, periodic), bin `bin`.
double brute_mean(const ParallaxTable& t, int bin, double x0, double y0, double x1, double y1) {
  const int n = t.resolution;
  double sum = 0;
  for (long ty = long(std::floor(y0)); ty < long(std::ceil(y1)); ++ty) {
    double hy = std::min(y1, double(ty + 1)) - std::max(y0, double(ty));
    if (hy <= 0) continue;
    for (long tx = long(std::floor(x0)); tx < long(std::ceil(x1)); ++tx) {
      double hx = std::min(x1, double(tx + 1)) - std::max(x0, double(tx));
      if (hx <= 0) continue;
      int x = int(((tx % n) + n) % n), y = int(((ty % n) + n) % n);
      sum += hx * hy * t.r(bin, x, y);
    }
  }
  return sum / ((x1 - x0) * (y1 - y0));
}

}  // namespace

TEST(ParallaxSections, RoundTripAndPerTexelQueries) {
  FabricMaps maps = rctest::plain_weave_maps(16);
  ParallaxSettings settings;
  settings.dirs = 8;
  ParallaxTable table = bake_parallax(maps, settings);
  ParallaxTable copy = table;
  MemoryAsset m(with_metadata(parallax_sections(std::move(table))));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  EXPECT_TRUE(view.has_sat());
  EXPECT_EQ(view.resolution(), 16u);
  EXPECT_EQ(view.dirs(), 8u);
  EXPECT_EQ(view.info().depth_scale, copy.depth_scale);
  EXPECT_EQ(view.info().reference_height, copy.reference_height);
  EXPECT_EQ(view.info().max_offset, copy.stats.max_sideways);
  model::DirectionGrid<double> grid{8, 0.6};
  for (int bin = 0; bin < 64; ++bin)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        ASSERT_EQ(view.bin_depth(uint32_t(bin), x, y), copy.r(bin, x, y));
        ASSERT_EQ(view.bin_depth(uint32_t(bin), x - 16, y + 32), copy.r(bin, x, y));  // wraps
      }
  // At a bin centre the query returns that bin; in between, the bilinear mix; Eq. 2 offsets.
  std::mt19937_64 rng(1);
  for (int k = 0; k < 500; ++k) {
    int x = int(rng() % 16), y = int(rng() % 16);
    Vec3d o = grid.direction(double(rng() % 1000) / 999.0, double(rng() % 1000) / 999.0);
    double v[3] = {o.x * 2, o.y * 2, o.z * 2};  // not normalised on purpose
    reader::ParallaxSample s;
    ASSERT_TRUE(view.depth(x, y, v, &s).ok());
    model::BinBilinear<double> w = grid.bilinear_fast(o);
    double expected = 0;
    for (int i = 0; i < 4; ++i)
      expected += w.weight[i] * copy.r(w.index[i], x, y);
    ASSERT_NEAR(s.r, expected, 1e-12);
    ASSERT_NEAR(s.offset[0], expected / o.z * o.x, 1e-12);
    ASSERT_NEAR(s.offset[1], expected / o.z * o.y, 1e-12);
  }
  Vec3d centre = grid.bin_center(3, 5);
  double c[3] = {centre.x, centre.y, centre.z};
  reader::ParallaxSample s;
  ASSERT_TRUE(view.depth(7, 9, c, &s).ok());
  // The direction lookup (DirectionGrid::bilinear_fast: the concentric map without atan2) puts
  // at most n * 1e-8 of the weight off a bin centre's own bin.
  EXPECT_NEAR(s.r, copy.r(grid.bin_index(3, 5), 7, 9), 8e-8 * 0.25);
}

TEST(ParallaxSections, DirectionsBelowTheCapUseTheRim) {
  ParallaxTable t = random_table(8, 8, 3);
  ParallaxTable copy = t;
  MemoryAsset m(with_metadata(parallax_sections(std::move(t))));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  const double below[3] = {0.9, 0.3, 0.05};  // 87 degrees: below the 0.6 cut
  reader::ParallaxSample s;
  ASSERT_TRUE(view.depth(2, 3, below, &s).ok());
  EXPECT_NEAR(s.direction[2], 0.6, 1e-15);
  EXPECT_NEAR(s.direction[1] / s.direction[0], 0.3 / 0.9, 1e-12);  // same azimuth
  EXPECT_TRUE(std::isfinite(s.offset[0]) && std::isfinite(s.offset[1]));
  // |offset| = |r| tan(theta_cut) = |r| 4/3 at most.
  EXPECT_NEAR(std::hypot(s.offset[0], s.offset[1]), -s.r * 4.0 / 3.0, 1e-12);
  const double down[3] = {0, 0, -1}, zero[3] = {0, 0, 0}, nan[3] = {NAN, 0, 1};
  EXPECT_TRUE(view.depth(0, 0, down, &s).ok());
  EXPECT_TRUE(std::isfinite(s.r));
  EXPECT_EQ(view.depth(0, 0, zero, &s).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(view.depth(0, 0, nan, &s).code(), ErrorCode::InvalidArgument);
}

TEST(ParallaxSections, FootprintMeansMatchBruteForce) {
  const int n = 16;
  ParallaxTable t = random_table(n, 4, 5);
  ParallaxTable copy = t;
  MemoryAsset m(with_metadata(parallax_sections(std::move(t))));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  model::DirectionGrid<double> grid{4, 0.6};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> corner(-40, 40), size(0, 1);
  for (int k = 0; k < 400; ++k) {
    // Sizes from a fraction of a texel to several tiles; corners anywhere.
    double w = k % 4 == 0 ? size(rng) * 0.8 : (k % 4 == 1 ? size(rng) * 10 : size(rng) * 70);
    double h = k % 3 == 0 ? size(rng) * 0.5 : size(rng) * 50;
    double x0 = corner(rng), y0 = corner(rng);
    int bin = int(rng() % 16);
    Vec3d o = grid.bin_center(bin % 4, bin / 4);
    double v[3] = {o.x, o.y, o.z};
    reader::ParallaxSample s;
    ASSERT_TRUE(view.footprint_depth({x0, y0, x0 + w, y0 + h}, v, &s).ok());
    // Brute-force footprint means of the bins the reader's direction lookup weights (a bin
    // centre gets almost all of the weight; the lookup itself is tested in tests/model).
    const model::BinBilinear<double> bw = grid.bilinear_fast(o);
    double expected = 0;
    for (int i = 0; i < 4; ++i)
      if (bw.weight[i] != 0)
        expected += bw.weight[i] * brute_mean(copy, bw.index[i], x0, y0, x0 + w, y0 + h);
    ASSERT_NEAR(s.r, expected, 1e-9 * (1 + std::abs(expected)))
        << "rect " << x0 << " " << y0 << " " << w << " " << h;
  }
  // A one-texel footprint equals the texel; zero area gives the texel containing the corner.
  Vec3d o = grid.bin_center(1, 2);
  double v[3] = {o.x, o.y, o.z};
  reader::ParallaxSample s;
  ASSERT_TRUE(view.footprint_depth({5, 6, 6, 7}, v, &s).ok());
  EXPECT_NEAR(s.r, copy.r(grid.bin_index(1, 2), 5, 6), 4e-8 * 0.25);  // lookup: <= n * 1e-8
  ASSERT_TRUE(view.footprint_depth({5.5, 6.5, 5.5, 6.5}, v, &s).ok());
  EXPECT_NEAR(s.r, copy.r(grid.bin_index(1, 2), 5, 6), 4e-8 * 0.25);
  EXPECT_EQ(view.footprint_depth({1, 1, 0, 2}, v, &s).code(), ErrorCode::InvalidArgument);
}

TEST(ParallaxSections, FarCornerOfTheLargestTableIsExact) {
  // The paper's resolution (256^2; two directions suffice: precision does not depend on them).
  // The largest codes make the SAT's last entries 65535 * 65536, just below 2^32.
  ParallaxTable t = random_table(256, 2, 11);
  for (std::size_t i = 0; i < t.depth.size(); i += 3)
    t.depth[i] = 65535;
  ParallaxTable copy = t;
  MemoryAsset m(with_metadata(parallax_sections(std::move(t))));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  model::DirectionGrid<double> grid{2, 0.6};
  for (int bin = 0; bin < 4; ++bin) {
    Vec3d o = grid.bin_center(bin % 2, bin / 2);
    double v[3] = {o.x, o.y, o.z};
    reader::ParallaxSample s;
    const uint32_t b = uint32_t(bin);
    // The SAT difference at the far corner is the texel's code, exactly.
    EXPECT_EQ(view.code_prefix_sum(b, 256, 256) - view.code_prefix_sum(b, 255, 256) -
                  view.code_prefix_sum(b, 256, 255) + view.code_prefix_sum(b, 255, 255),
              copy.depth[std::size_t(bin) * 65536 + 65535]);
    const double expected = copy.r(bin, 255, 255);
    ASSERT_TRUE(view.footprint_depth({255, 255, 256, 256}, v, &s).ok());
    EXPECT_NEAR(s.r, expected, 1e-15) << "bin " << bin;
    ASSERT_TRUE(view.footprint_depth({-1, -1, 0, 0}, v, &s).ok());  // the same texel, wrapped
    EXPECT_NEAR(s.r, expected, 1e-15);
    uint64_t total = 0;
    for (int y = 0; y < 256; ++y)
      for (int x = 0; x < 256; ++x)
        total += copy.depth[std::size_t(bin) * 65536 + y * 256 + x];
    EXPECT_EQ(view.code_prefix_sum(uint32_t(bin), 256, 256), total);
  }
}

TEST(ParallaxSections, SumsBeyond2To32AreExactOnLargeTables) {
  // 512^2 texels all at the largest code: the tile sums to 65535 * 2^18 > 2^32; the reader sums
  // in bands and stays exact; the footprint mean of any rectangle is exactly the code.
  ParallaxTable t;
  t.resolution = 512;
  t.dirs = 1;
  t.min_cos = 0.6;
  t.depth_scale = 1.0 / 65535.0;
  t.depth.assign(512u * 512u, 65535);
  MemoryAsset m(with_metadata(parallax_sections(std::move(t))));
  reader::ParallaxView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  EXPECT_EQ(view.code_prefix_sum(0, 512, 512), uint64_t(65535) * 512 * 512);
  EXPECT_EQ(view.code_prefix_sum(0, 300, 499), uint64_t(65535) * 300 * 499);
  const double up[3] = {0, 0, 1};
  reader::ParallaxSample s;
  ASSERT_TRUE(view.footprint_depth({-700.25, 13.5, 1800.75, 2000}, up, &s).ok());
  EXPECT_NEAR(s.r, -1.0, 1e-12);
}

TEST(ParallaxSections, HostileSectionsAreRejected) {
  ParallaxTable t = random_table(8, 2, 13);
  auto sections = parallax_sections(ParallaxTable(t));
  auto open_with = [&](std::vector<formats::Section> s) {
    MemoryAsset m(with_metadata(std::move(s)));
    EXPECT_TRUE(m.status.ok()) << m.status.message();
    reader::ParallaxView view;
    return view.open(m.asset);
  };
  EXPECT_TRUE(open_with(sections).ok());
  {  // no table at all
    reader::Status s = open_with({});
    EXPECT_EQ(s.code(), ErrorCode::NotFound);
    EXPECT_EQ(s.check(), reader::Check::MissingSection);
  }
  {  // a newer payload version
    auto s = sections;
    s[1].version = 2;
    EXPECT_EQ(open_with(s).code(), ErrorCode::Unsupported);
  }
  {  // info out of range: zero directions, NaN-free but absurd scale
    auto s = sections;
    reader::ParallaxInfoRecord info;
    std::memcpy(&info, s[0].payload.data(), sizeof info);
    info.dirs = 0;
    std::memcpy(s[0].payload.data(), &info, sizeof info);
    EXPECT_EQ(open_with(s).check(), reader::Check::ValueRange);
    info.dirs = 2;
    info.min_cos = 1.5;
    std::memcpy(s[0].payload.data(), &info, sizeof info);
    EXPECT_EQ(open_with(s).check(), reader::Check::ValueRange);
  }
  {  // codes of the wrong shape
    auto s = sections;
    s[1].dims = {4, 8, 4};
    s[1].payload.resize(4 * 8 * 4 * 2);
    EXPECT_EQ(open_with(s).code(), ErrorCode::WrongType);
  }
  {  // SAT disagreeing with the table
    auto s = sections;
    s[2].dims = {4, 4, 16};
    EXPECT_EQ(open_with(s).code(), ErrorCode::WrongType);
  }
  {  // codes stored as another element type
    auto s = sections;
    s[1].element = reader::ElementType::I16;
    EXPECT_EQ(open_with(s).code(), ErrorCode::WrongType);
  }
  {  // no SAT: per-texel queries work, footprint queries say what is missing
    auto s = sections;
    s.pop_back();
    MemoryAsset m(with_metadata(s));
    reader::ParallaxView view;
    ASSERT_TRUE(view.open(m.asset).ok());
    EXPECT_FALSE(view.has_sat());
    const double up[3] = {0, 0, 1};
    reader::ParallaxSample sample;
    EXPECT_TRUE(view.depth(0, 0, up, &sample).ok());
    EXPECT_EQ(view.footprint_depth({0, 0, 2, 2}, up, &sample).code(), ErrorCode::NotFound);
  }
}

TEST(VisibilitySections, RoundTripAndQueries) {
  FabricMaps maps = rctest::plain_weave_maps(16);
  VisibilitySettings settings;
  settings.dirs = 12;
  VisibilitySamples samples = sample_visibility(maps, settings);
  VisibilityAsgs asgs = fit_visibility(samples, settings);
  MemoryAsset m(with_metadata(visibility_sections(asgs, settings, settings.dirs)));
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  reader::VisibilityAsgView view;
  ASSERT_TRUE(view.open(m.asset).ok());
  EXPECT_TRUE(view.has_fit_error());
  EXPECT_EQ(view.info().dirs, 12u);
  EXPECT_EQ(view.info().mean_fit_error, asgs.mean_fit_error);
  std::vector<model::AsgParams<float>> lobes = decoded_lobes(asgs);
  std::mt19937_64 rng(2);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      std::size_t t = std::size_t(y) * 16 + x;
      model::AsgRecord r = view.record(x + 16, y - 32);  // wraps
      ASSERT_EQ(std::memcmp(&r, &asgs.records[t], sizeof r), 0);
      ASSERT_EQ(view.fit_error(x, y), double(asgs.fit_error[t]));
      model::Asg<double> g = model::asg_from_params(model::unpack_asg<double>(asgs.records[t]));
      for (int k = 0; k < 10; ++k) {
        double w[3] = {double(rng() % 200) - 100, double(rng() % 200) - 100,
                       double(rng() % 100) + 1};
        double v;
        ASSERT_TRUE(view.visibility(x, y, w, &v).ok());
        double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        double expected = model::asg_eval(g, Vec3d(w[0] / len, w[1] / len, w[2] / len));
        ASSERT_NEAR(v, std::clamp(expected, 0.0, 1.0), 1e-12);
      }
      ASSERT_FLOAT_EQ(lobes[t].lambda, float(model::unpack_asg<double>(asgs.records[t]).lambda));
    }
  double v;
  const double zero[3] = {0, 0, 0};
  EXPECT_EQ(view.visibility(0, 0, zero, &v).code(), ErrorCode::InvalidArgument);
}

TEST(VisibilitySections, HostileSectionsAreRejected) {
  VisibilityAsgs asgs;
  asgs.resolution = 4;
  asgs.records.resize(16);
  asgs.fit_error.assign(16, 0.1f);
  VisibilitySettings settings;
  auto sections = visibility_sections(asgs, settings, 8);
  auto open_with = [&](std::vector<formats::Section> s) {
    MemoryAsset m(with_metadata(std::move(s)));
    EXPECT_TRUE(m.status.ok()) << m.status.message();
    reader::VisibilityAsgView view;
    return view.open(m.asset);
  };
  EXPECT_TRUE(open_with(sections).ok());
  EXPECT_EQ(open_with({}).code(), ErrorCode::NotFound);
  {  // another record encoding
    auto s = sections;
    reader::VisibilityInfoRecord info;
    std::memcpy(&info, s[0].payload.data(), sizeof info);
    info.max_bandwidth = 1000;
    std::memcpy(s[0].payload.data(), &info, sizeof info);
    EXPECT_EQ(open_with(s).code(), ErrorCode::Unsupported);
  }
  {  // records of 5 fields
    auto s = sections;
    s[1].dims = {4, 4, 5};
    s[1].payload.resize(4 * 4 * 5 * 2);
    EXPECT_EQ(open_with(s).code(), ErrorCode::WrongType);
  }
  {  // a fit error out of range
    auto s = sections;
    float bad = 7.0f;
    std::memcpy(s[2].payload.data() + 4 * 5, &bad, 4);
    reader::Status st = open_with(s);
    EXPECT_EQ(st.check(), reader::Check::ValueRange);
    EXPECT_NE(std::string(st.message()).find("texel (1, 1)"), std::string::npos) << st.message();
  }
}

TEST(RaycastStages, BakeWritesQueryableSectionsIdenticallyForAnyThreadCount) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("clothbake_raycast_stage_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  Fabric fabric = fabric_from_named_weave("plain", 16).fabric;
  fabric.bake.parallax_dirs = 8;
  fabric.bake.visibility_dirs = 8;
  std::vector<std::vector<char>> bytes;
  for (int threads : {1, 2}) {
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.output_path = (dir / (threads == 1 ? "t1.cbk" : "t2.cbk")).string();
    request.stages = {"parallax", "visibility"};
    request.run.threads = threads;
    pipeline::bake(request, stages::bake_stages());
    std::ifstream in(request.output_path, std::ios::binary);
    bytes.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  EXPECT_EQ(bytes[0], bytes[1]);
  reader::Asset asset;
  ASSERT_TRUE(asset.open_file((dir / "t1.cbk").c_str()).ok());
  reader::ParallaxView parallax;
  reader::VisibilityAsgView visibility;
  ASSERT_TRUE(parallax.open(asset).ok());
  ASSERT_TRUE(visibility.open(asset).ok());
  // The stages computed what the library computes.
  ParallaxSettings ps;
  ps.dirs = 8;
  ParallaxTable direct = bake_parallax(fabric.maps, ps);
  // The default form is the compressed one (8-bit codes, within the recorded error).
  ASSERT_TRUE(parallax.is_compressed());
  for (int bin = 0; bin < 64; bin += 5)
    for (int x = 0; x < 16; ++x)
      ASSERT_LE(std::fabs(parallax.bin_depth(uint32_t(bin), x, 3) - direct.r(bin, x, 3)),
                parallax.compressed_info().max_depth_error);
  // Without compression the stage writes the raw codes exactly (format 1.0).
  {
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.fabric->bake.compress = false;
    request.output_path = (dir / "raw.cbk").string();
    request.stages = {"parallax"};
    pipeline::bake(request, stages::bake_stages());
    reader::Asset raw_asset;
    ASSERT_TRUE(raw_asset.open_file(request.output_path.c_str()).ok());
    EXPECT_EQ(raw_asset.version_minor(), 0);
    reader::ParallaxView raw;
    ASSERT_TRUE(raw.open(raw_asset).ok());
    EXPECT_FALSE(raw.is_compressed());
    for (int bin = 0; bin < 64; bin += 5)
      for (int x = 0; x < 16; ++x)
        ASSERT_EQ(raw.bin_depth(uint32_t(bin), x, 3), direct.r(bin, x, 3));
  }
  std::string_view json;
  ASSERT_TRUE(asset.metadata_json(&json).ok());
  auto meta = nlohmann::json::parse(json);
  EXPECT_EQ(meta["parameters"]["parallax"]["dirs"], 8);
  EXPECT_EQ(meta["parameters"]["visibility"]["dirs"], 8);
  fs::remove_all(dir);
}

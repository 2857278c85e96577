// Footprint queries on raw Integral-Radiance tables through the reader library
// (formats/reader/radiance_query.hpp, formats/reader_raw/radiance_tables.hpp), on assets written
// with the writer: exactness against direct sums over the same texels and bins, the precision
// target at 256^2 and 2048^2 (far corner included), periodicity, bin interpolation, argument
// errors, hostile sections.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "formats/reader/asset.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"
#include "tests/support/table_fixtures.hpp"

using namespace clothbake;
using namespace clothbake::tables;
using clothbake::tables_testing::synthetic_fabric;
using reader::Footprint;
using reader::RadianceTableKind;
using reader::RawRadianceTables;

namespace {

// An asset in memory holding the given sets (the buffer must outlive the Asset).
struct MemoryAsset {
  std::vector<std::byte> bytes;
  reader::Asset asset;
};

std::unique_ptr<MemoryAsset> write_asset(std::vector<RadianceTableSet> sets,
                                         void (*mutate)(std::vector<formats::Section>&) = nullptr) {
  std::vector<formats::Section> sections;
  for (auto& s : sets)
    for (auto& sec : radiance_sections(std::move(s)))
      sections.push_back(std::move(sec));
  if (mutate) mutate(sections);
  auto out = std::make_unique<MemoryAsset>();
  out->bytes = formats::serialize_asset(sections);
  reader::Status st = out->asset.open_memory(out->bytes.data(), out->bytes.size());
  EXPECT_TRUE(st.ok()) << st.message();
  return out;
}

// Covered length of texel column i (mod n) by [a0, a1), summed over every period.
std::vector<double> coverage(double a0, double a1, int n) {
  std::vector<double> w(std::size_t(n), 0.0);
  for (double i = std::floor(a0); i < a1; i += 1.0) {
    const double lo = std::max(a0, i), hi = std::min(a1, i + 1.0);
    if (hi <= lo) continue;
    long m = long(std::fmod(i, double(n)));
    if (m < 0) m += n;
    w[std::size_t(m)] += hi - lo;
  }
  return w;
}

// Direct sum over texels of value(bin, x, y) weighted by coverage and bin weights.
template <class Value>
double direct_sum(const Footprint& r, int n, const reader::BinWeights& bw, Value&& value) {
  const auto wx = coverage(r.x0, r.x1, n), wy = coverage(r.y0, r.y1, n);
  double total = 0;
  for (uint32_t k = 0; k < bw.count; ++k) {
    double s = 0;
    for (int y = 0; y < n; ++y) {
      if (wy[std::size_t(y)] == 0) continue;
      double row = 0;
      for (int x = 0; x < n; ++x)
        if (wx[std::size_t(x)] != 0) row += wx[std::size_t(x)] * value(int(bw.bin[k]), x, y);
      s += wy[std::size_t(y)] * row;
    }
    total += bw.weight[k] * s;
  }
  return total;
}

Footprint random_footprint(std::mt19937_64& rng, int n, bool integer) {
  std::uniform_real_distribution<double> pos(-3.0 * n, 3.0 * n);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Sizes spread over every class: sub-texel to several tiles.
  const double size_x = std::pow(2.0, unit(rng) * (std::log2(double(n)) + 2.5)) - 0.5;
  const double size_y = std::pow(2.0, unit(rng) * (std::log2(double(n)) + 2.5)) - 0.5;
  Footprint f;
  f.x0 = pos(rng);
  f.y0 = pos(rng);
  f.x1 = f.x0 + std::max(size_x, 0.0);
  f.y1 = f.y0 + std::max(size_y, 0.0);
  if (integer) {
    f.x0 = std::floor(f.x0);
    f.y0 = std::floor(f.y0);
    f.x1 = std::max(f.x0 + 1, std::floor(f.x1));
    f.y1 = std::max(f.y0 + 1, std::floor(f.y1));
  }
  return f;
}

model::Vec3d random_h(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return model::normalize(model::Vec3d(g(rng), g(rng), g(rng)));
}

}  // namespace

TEST(RadianceQuery, ExactAgainstDirectSumsOfTheStoredTexels) {
  auto f = synthetic_fabric(24, 3);
  RadianceOptions o;
  o.bins_per_side = 6;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  RadianceTableSet set = build_specular_tables(f.inputs(), o);
  const RadianceTableSet copy = set;  // keeps the SAT for direct sums
  auto a = write_asset({std::move(set)});
  RawRadianceTables tables;
  ASSERT_TRUE(tables.open(a->asset, RadianceTableKind::Specular).ok());
  EXPECT_EQ(tables.resolution(), 24u);
  EXPECT_EQ(tables.bins_per_side(), 6u);
  EXPECT_EQ(tables.cluster_count(), 3u);
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 400; ++trial) {
    const Footprint r = random_footprint(rng, 24, trial % 2 == 0);
    const model::Vec3d h = random_h(rng);
    const double hv[3] = {h.x, h.y, h.z};
    reader::BinWeights bw;
    ASSERT_TRUE(reader::radiance_bin_weights(6, hv, &bw).ok());
    double all[3];
    ASSERT_TRUE(tables.query_all(r, hv, all).ok());
    for (int k = 0; k < 3; ++k) {
      double one = -1;
      ASSERT_TRUE(tables.query(r, hv, uint32_t(k), &one).ok());
      const double direct =
          direct_sum(r, 24, bw, [&](int b, int x, int y) { return copy.texel_value(b, x, y, k); });
      // The only rounding left is double arithmetic on the fractional parts and the scaling.
      ASSERT_NEAR(one, direct, 1e-12 * std::max(1.0, direct))
          << "trial " << trial << " cluster " << k << " rect [" << r.x0 << "," << r.x1 << ")x["
          << r.y0 << "," << r.y1 << ")";
      ASSERT_NEAR(all[k], one, 1e-12 * std::max(1.0, one));
    }
  }
}

TEST(RadianceQuery, MeetsThePrecisionTargetAt256IncludingTheFarCorner) {
  // 256^2 texels, 8 clusters, a narrow (satin) and a broad yarn; 4^2 bins keep the test fast.
  // Error metric (docs/tables.md): |F - direct| / max(direct, A * mean), mean = the table's mean
  // texel value, A the footprint area; direct = the same sum over the unquantised values.
  auto f = synthetic_fabric(256, 8, 0.04, 0.3);
  RadianceOptions o;
  o.bins_per_side = 4;
  o.samples_per_side = 2;
  o.warn_unresolved = false;
  RadianceTableSet set = build_specular_tables(f.inputs(), o);
  ASSERT_EQ(set.info.element_bits, 32u);
  auto a = write_asset({std::move(set)});
  RawRadianceTables tables;
  ASSERT_TRUE(tables.open(a->asset, RadianceTableKind::Specular).ok());
  const HalfVectorBins bins = make_half_vector_bins(4, 2);
  std::vector<std::vector<float>> values(16, std::vector<float>(256 * 256));
  std::vector<std::vector<double>> mean(16, std::vector<double>(8, 0.0));
  for (int b = 0; b < 16; ++b) {
    radiance_bin_values(RadianceTableKind::Specular, f.inputs(), bins, b,
                        values[std::size_t(b)].data());
    for (std::size_t t = 0; t < values[std::size_t(b)].size(); ++t)
      mean[std::size_t(b)][f.labels[t]] += values[std::size_t(b)][t] / (256.0 * 256.0);
  }
  std::mt19937_64 rng(2);
  std::vector<Footprint> rects;
  rects.push_back({255, 255, 256, 256});       // one texel at the far corner
  rects.push_back({0, 0, 1, 1});               // and at the near corner
  rects.push_back({255.5, 255.25, 256, 256});  // part of the far corner texel
  rects.push_back({-0.5, -0.5, 0.5, 0.5});     // four quarter texels across the wrap
  for (int i = 0; i < 60; ++i)
    rects.push_back(random_footprint(rng, 256, i % 3 == 0));
  double worst = 0, worst_pure = 0;
  for (const Footprint& r : rects) {
    const model::Vec3d h = random_h(rng);
    const double hv[3] = {h.x, h.y, h.z};
    reader::BinWeights bw;
    ASSERT_TRUE(reader::radiance_bin_weights(4, hv, &bw).ok());
    double q[8];
    ASSERT_TRUE(tables.query_all(r, hv, q).ok());
    const double area = (r.x1 - r.x0) * (r.y1 - r.y0);
    for (int c = 0; c < 8; ++c) {
      const double direct = direct_sum(r, 256, bw, [&](int b, int x, int y) {
        const std::size_t t = std::size_t(y) * 256 + std::size_t(x);
        return f.labels[t] == c ? double(values[std::size_t(b)][t]) : 0.0;
      });
      double level = 0;
      for (uint32_t k = 0; k < bw.count; ++k)
        level += bw.weight[k] * mean[bw.bin[k]][std::size_t(c)];
      const double floor = area * level;
      const double err = std::abs(q[c] - direct) / std::max(direct, floor);
      worst = std::max(worst, err);
      if (direct >= floor) worst_pure = std::max(worst_pure, std::abs(q[c] - direct) / direct);
      ASSERT_LE(err, 1e-5) << "cluster " << c << " rect [" << r.x0 << "," << r.x1 << ")x[" << r.y0
                           << "," << r.y1 << ") direct " << direct << " query " << q[c];
    }
  }
  RecordProperty("worst_relative_error_256", std::to_string(worst));
  RecordProperty("worst_pure_relative_error_256", std::to_string(worst_pure));
}

TEST(RadianceQuery, MeetsThePrecisionTargetAt2048) {
  // One bin, one cluster, 2048^2 texels: u64 elements (u32 would give 4.9e-4 here).
  const int n = 2048;
  auto f = synthetic_fabric(n, 1, 0.3, 0.1);
  RadianceOptions o;
  o.bins_per_side = 1;
  o.samples_per_side = 4;
  o.warn_unresolved = false;
  RadianceTableSet set = build_specular_tables(f.inputs(), o);
  ASSERT_EQ(set.info.element_bits, 64u);
  auto a = write_asset({std::move(set)});
  RawRadianceTables tables;
  ASSERT_TRUE(tables.open(a->asset, RadianceTableKind::Specular).ok());
  std::vector<float> v(std::size_t(n) * n);
  radiance_bin_values(RadianceTableKind::Specular, f.inputs(), make_half_vector_bins(1, 4), 0,
                      v.data());
  double mean = 0;
  for (float x : v)
    mean += x / (double(n) * n);
  std::mt19937_64 rng(3);
  std::vector<Footprint> rects = {{2047, 2047, 2048, 2048}, {2047.5, 2047.5, 2048, 2048}};
  for (int i = 0; i < 12; ++i) {
    Footprint r = random_footprint(rng, n, i % 2 == 0);
    r.x1 = std::min(r.x1, r.x0 + 3000);  // keep the direct sums short
    r.y1 = std::min(r.y1, r.y0 + 3000);
    rects.push_back(r);
  }
  const double hv[3] = {0, 0, 1};
  reader::BinWeights bw;
  ASSERT_TRUE(reader::radiance_bin_weights(1, hv, &bw).ok());
  for (const Footprint& r : rects) {
    double q;
    ASSERT_TRUE(tables.query(r, hv, 0, &q).ok());
    const double direct = direct_sum(r, n, bw, [&](int, int x, int y) {
      return double(v[std::size_t(y) * std::size_t(n) + std::size_t(x)]);
    });
    const double area = (r.x1 - r.x0) * (r.y1 - r.y0);
    EXPECT_LE(std::abs(q - direct) / std::max(direct, area * mean), 1e-4)
        << "rect [" << r.x0 << "," << r.x1 << ")x[" << r.y0 << "," << r.y1 << ")";
  }
}

TEST(RadianceQuery, PeriodicAndAdditive) {
  auto f = synthetic_fabric(16, 2);
  RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  auto a = write_asset(build_radiance_tables(f.inputs(), o));
  RawRadianceTables spec;
  ASSERT_TRUE(spec.open(a->asset, RadianceTableKind::Specular).ok());
  const double h[3] = {0.2, -0.1, 0.9};
  double tile[2];
  ASSERT_TRUE(spec.query_all({0, 0, 16, 16}, h, tile).ok());
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  for (int i = 0; i < 50; ++i) {
    const double x0 = u(rng), y0 = u(rng);
    double any[2], shifted[2], two[2];
    // Any full-tile window integrates the whole tile.
    ASSERT_TRUE(spec.query_all({x0, y0, x0 + 16, y0 + 16}, h, any).ok());
    // Whole-tile shifts do not change a footprint.
    const Footprint r{x0, y0, x0 + 5.5, y0 + 3.25};
    ASSERT_TRUE(spec.query_all(r, h, shifted).ok());
    ASSERT_TRUE(spec.query_all({r.x0 + 32, r.y0 - 48, r.x1 + 32, r.y1 - 48}, h, two).ok());
    for (int c = 0; c < 2; ++c) {
      EXPECT_NEAR(any[c], tile[c], 1e-9 * tile[c]);
      EXPECT_NEAR(shifted[c], two[c], 1e-9 * tile[c]);
    }
    // Additivity: a 2.5 x 3 tile footprint is 2.5 * 3 tiles.
    double big[2];
    ASSERT_TRUE(spec.query_all({x0, y0, x0 + 40, y0 + 48}, h, big).ok());
    for (int c = 0; c < 2; ++c)
      EXPECT_NEAR(big[c], 7.5 * tile[c], 1e-6 * tile[c]);
  }
  // The gap table ignores h (even a zero one) and holds 1 - I.
  RawRadianceTables gap;
  ASSERT_TRUE(gap.open(a->asset, RadianceTableKind::Gap).ok());
  EXPECT_EQ(gap.bins_per_side(), 1u);
  const double zero[3] = {0, 0, 0};
  double g[2];
  ASSERT_TRUE(gap.query_all({0, 0, 16, 16}, zero, g).ok());
  double expect = 0;
  for (float v : f.gap)
    expect += 1.0 - v;
  EXPECT_NEAR(g[0] + g[1], expect, 1e-6 * expect);
}

TEST(RadianceQuery, BinInterpolationAndFolding) {
  auto f = synthetic_fabric(8, 1);
  RadianceOptions o;
  o.bins_per_side = 8;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  RadianceTableSet set = build_specular_tables(f.inputs(), o);
  const RadianceTableSet copy = set;
  auto a = write_asset({std::move(set)});
  RawRadianceTables t;
  ASSERT_TRUE(t.open(a->asset, RadianceTableKind::Specular).ok());
  model::DirectionGrid<double> grid{8, 0.0};
  const Footprint r{1, 2, 5, 7};
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) {
      // At a bin centre the answer is that bin's footprint sum; -h folds onto h.
      const model::Vec3d c = grid.bin_center(i, j);
      const double h[3] = {c.x, c.y, c.z}, mh[3] = {-c.x, -c.y, -c.z};
      double q, qm;
      ASSERT_TRUE(t.query(r, h, 0, &q).ok());
      ASSERT_TRUE(t.query(r, mh, 0, &qm).ok());
      double direct = 0;
      for (int y = 2; y < 7; ++y)
        for (int x = 1; x < 5; ++x)
          direct += copy.texel_value(grid.bin_index(i, j), x, y, 0);
      // Queries find bins through DirectionGrid::bilinear_fast (polynomial atan): at a bin centre
      // the neighbours' weights are below n * 1e-8.
      EXPECT_NEAR(q, direct, 1e-7 * direct);
      EXPECT_EQ(q, qm);
      // Unnormalised h gives the same answer.
      const double h3[3] = {3 * c.x, 3 * c.y, 3 * c.z};
      double q3;
      ASSERT_TRUE(t.query(r, h3, 0, &q3).ok());
      EXPECT_NEAR(q3, q, 1e-12 * q);
    }
}

TEST(RadianceQuery, ArgumentErrorsAreReportedNotCrashes) {
  auto f = synthetic_fabric(8, 2);
  f.labels.assign(f.labels.size(), 0);  // cluster 1 has no texel: not stored
  RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  auto a = write_asset({build_specular_tables(f.inputs(), o)});
  RawRadianceTables t;
  ASSERT_TRUE(t.open(a->asset, RadianceTableKind::Specular).ok());
  EXPECT_EQ(t.column_of_cluster(1), -1);
  const double h[3] = {0, 0, 1}, zero[3] = {0, 0, 0}, nan[3] = {NAN, 0, 1};
  double q = -1;
  EXPECT_TRUE(t.query({0, 0, 2, 2}, h, 1, &q).ok());
  EXPECT_EQ(q, 0.0);  // no table: zero
  using reader::ErrorCode;
  EXPECT_EQ(t.query({0, 0, 2, 2}, h, 2, &q).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query({0, 0, 2, 2}, zero, 0, &q).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query({0, 0, 2, 2}, nan, 0, &q).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query({2, 0, 1, 2}, h, 0, &q).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query({NAN, 0, 1, 2}, h, 0, &q).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query({0, 0, 1e30, 2}, h, 0, &q).code(), ErrorCode::InvalidArgument);
  EXPECT_EQ(t.query({0, 0, 2, 2}, h, 0, nullptr).code(), ErrorCode::InvalidArgument);
  // An empty footprint is zero.
  EXPECT_TRUE(t.query({3, 3, 3, 5}, h, 0, &q).ok());
  EXPECT_EQ(q, 0.0);
  RawRadianceTables gap;
  EXPECT_EQ(gap.open(a->asset, RadianceTableKind::Gap).code(), ErrorCode::NotFound);
  EXPECT_EQ(gap.query({0, 0, 1, 1}, h, 0, &q).code(), ErrorCode::InvalidArgument);  // not open
}

TEST(RadianceQuery, HostileSectionsAreRejectedAtOpen) {
  auto f = synthetic_fabric(8, 2);
  RadianceOptions o;
  o.bins_per_side = 2;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  using Mutator = void (*)(std::vector<formats::Section>&);
  auto info_of = [](std::vector<formats::Section>& s) {
    return reinterpret_cast<reader::RadianceTableInfoRecord*>(s[0].payload.data());
  };
  (void)info_of;
  const Mutator mutations[] = {
      [](std::vector<formats::Section>& s) {
        reinterpret_cast<reader::RadianceTableInfoRecord*>(s[0].payload.data())->resolution = 9;
      },
      [](std::vector<formats::Section>& s) {
        reinterpret_cast<reader::RadianceTableInfoRecord*>(s[0].payload.data())->element_bits = 64;
      },
      [](std::vector<formats::Section>& s) {
        reinterpret_cast<reader::RadianceTableInfoRecord*>(s[0].payload.data())->bins_per_side =
            70000;
      },
      [](std::vector<formats::Section>& s) {
        reinterpret_cast<reader::RadianceTableInfoRecord*>(s[0].payload.data())->cluster_count = 1;
      },
      [](std::vector<formats::Section>& s) {
        reinterpret_cast<reader::RadianceTableInfoRecord*>(s[0].payload.data())->kind = 1;
      },
      [](std::vector<formats::Section>& s) {  // cluster ids not ascending
        auto* ids = reinterpret_cast<uint32_t*>(s[1].payload.data());
        std::swap(ids[0], ids[1]);
      },
      [](std::vector<formats::Section>& s) {  // a NaN unit would poison every answer
        const double bad = -1.0;
        std::memcpy(s[2].payload.data(), &bad, sizeof bad);
      },
      [](std::vector<formats::Section>& s) {
        s[3].dims[1] = 4;
        s[3].payload.resize(s[3].payload.size() / 2);
      },
      [](std::vector<formats::Section>& s) { s[2].version = 2; },
  };
  int index = 0;
  for (Mutator m : mutations) {
    auto a = write_asset({build_specular_tables(f.inputs(), o)}, m);
    RawRadianceTables t;
    reader::Status st = t.open(a->asset, RadianceTableKind::Specular);
    EXPECT_FALSE(st.ok()) << "mutation " << index;
    EXPECT_FALSE(t.is_open());
    ++index;
  }
  // A SAT that decreases (cannot come from non-negative data) opens (O(1) checks) but fails the
  // content scan, naming the texel.
  auto a =
      write_asset({build_specular_tables(f.inputs(), o)}, [](std::vector<formats::Section>& s) {
        auto* sat = reinterpret_cast<uint32_t*>(s[3].payload.data());
        sat[(3 * 8 + 5) * 2 + 1] = 0;  // bin 0, texel (5, 3), column 1
      });
  RawRadianceTables t;
  ASSERT_TRUE(t.open(a->asset, RadianceTableKind::Specular).ok());
  reader::Status st = t.check_contents();
  EXPECT_FALSE(st.ok());
  EXPECT_NE(std::string(st.message()).find("texel (5, 3)"), std::string::npos) << st.message();
  auto good = write_asset({build_specular_tables(f.inputs(), o)});
  ASSERT_TRUE(t.open(good->asset, RadianceTableKind::Specular).ok());
  EXPECT_TRUE(t.check_contents().ok());
}

TEST(RadianceQuery, TexelImageHoldsTheTableValues) {
  auto f = synthetic_fabric(8, 3);
  f.labels.assign(f.labels.size(), 0);
  for (std::size_t t = 0; t < f.labels.size(); t += 2)
    f.labels[t] = 2;  // cluster 1 unused
  RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;
  RadianceTableSet set = build_specular_tables(f.inputs(), o);
  const RadianceTableSet copy = set;
  auto a = write_asset({std::move(set)});
  RawRadianceTables t;
  ASSERT_TRUE(t.open(a->asset, RadianceTableKind::Specular).ok());
  std::vector<float> image(64);
  ASSERT_TRUE(t.texel_image(5, 2, image.data()).ok());
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      EXPECT_FLOAT_EQ(image[std::size_t(y * 8 + x)], float(copy.texel_value(5, x, y, 1)));
  ASSERT_TRUE(t.texel_image(5, 1, image.data()).ok());
  for (float v : image)
    EXPECT_EQ(v, 0.0f);
  EXPECT_FALSE(t.texel_image(16, 0, image.data()).ok());
  EXPECT_FALSE(t.texel_image(0, 3, image.data()).ok());
}

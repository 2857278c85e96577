// The Integral-Radiance table fill (tables/radiance_fill.hpp): masks by cluster, bin averages
// against closed forms and fine quadrature, stored kinds and clusters, determinism, errors.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <vector>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "model/sggx.hpp"
#include "tables/radiance_fill.hpp"
#include "tests/support/table_fixtures.hpp"

using namespace clothbake;
using namespace clothbake::tables;
using clothbake::tables_testing::synthetic_fabric;

TEST(RadianceFill, TexelValuesAreTheMaskedBinAveragesWithinHalfAUnit) {
  auto f = synthetic_fabric(32, 3);
  RadianceOptions o;
  o.bins_per_side = 8;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  o.samples_per_side = 3;
  RadianceTableSet set = build_specular_tables(f.inputs(), o);
  ASSERT_EQ(set.columns(), 3);
  EXPECT_EQ(set.info.element_bits, 32u);
  EXPECT_EQ(set.info.samples_per_bin_side, 3u);
  const HalfVectorBins bins = make_half_vector_bins(8, 3);
  std::vector<float> v(32 * 32);
  for (int b = 0; b < 64; b += 7) {
    radiance_bin_values(RadianceTableKind::Specular, f.inputs(), bins, b, v.data());
    for (int k = 0; k < 3; ++k) {
      const double unit = set.units[std::size_t(b * 3 + k)];
      for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
          const std::size_t t = std::size_t(y * 32 + x);
          const double expect = f.labels[t] == set.clusters[std::size_t(k)] ? v[t] : 0.0;
          ASSERT_NEAR(set.texel_value(b, x, y, k), expect, 0.5 * unit * (1 + 1e-9))
              << "bin " << b << " column " << k << " texel " << x << "," << y;
        }
    }
  }
}

TEST(RadianceFill, BinAveragesIntegrateToTheClosedFormHemisphereIntegral) {
  // sum_b avg_b * (2 pi / n^2) is the hemisphere integral of D, whatever the tangent.
  for (double sigma : {0.5, 0.3, 0.1}) {
    auto f = synthetic_fabric(8, 1, sigma, sigma, /*gaps=*/false);
    const int n = 16, s = default_samples_per_side(n, sigma);
    const HalfVectorBins bins = make_half_vector_bins(n, s);
    std::vector<double> integral(64, 0.0);
    std::vector<float> v(64);
    for (int b = 0; b < n * n; ++b) {
      radiance_bin_values(RadianceTableKind::Specular, f.inputs(), bins, b, v.data());
      for (int t = 0; t < 64; ++t)
        integral[std::size_t(t)] += v[std::size_t(t)] * 2 * M_PI / (n * n);
    }
    const double expect = clothbake::tables_testing::sggx_hemisphere_integral(sigma);
    for (int t = 0; t < 64; ++t)
      EXPECT_NEAR(integral[std::size_t(t)], expect, 2e-3 * expect) << sigma;
  }
}

TEST(RadianceFill, DefaultQuadratureMatchesAFineReferenceForNarrowLobes) {
  // Bin averages with the default s against s = 16, for the paper's satin roughness 0.04 at 32^2:
  // error relative to the largest bin average stays at the percent level (docs/tables.md).
  auto f = synthetic_fabric(4, 1, 0.04, 0.04, false);
  const int n = 32, s = default_samples_per_side(n, 0.04);
  const HalfVectorBins coarse = make_half_vector_bins(n, s), fine = make_half_vector_bins(n, 16);
  std::vector<float> a(16), b(16);
  double worst = 0, peak = 0;
  for (int bin = 0; bin < n * n; ++bin) {
    radiance_bin_values(RadianceTableKind::Specular, f.inputs(), coarse, bin, a.data());
    radiance_bin_values(RadianceTableKind::Specular, f.inputs(), fine, bin, b.data());
    for (int t = 0; t < 16; ++t) {
      worst = std::max(worst, double(std::abs(a[std::size_t(t)] - b[std::size_t(t)])));
      peak = std::max(peak, double(b[std::size_t(t)]));
    }
  }
  EXPECT_LT(worst / peak, 0.02) << "worst " << worst << " peak " << peak;
}

TEST(RadianceFill, GapTableIsExactAndOnlyStoredWhenTheFabricHasGaps) {
  auto f = synthetic_fabric(16, 2);
  RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  RadianceTableSet gap = build_gap_tables(f.inputs(), o);
  ASSERT_EQ(gap.bins(), 1);
  ASSERT_EQ(gap.columns(), 2);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int k = 0; k < 2; ++k) {
        const std::size_t t = std::size_t(y * 16 + x);
        const double expect = f.labels[t] == gap.clusters[std::size_t(k)] ? 1.0 - f.gap[t] : 0.0;
        EXPECT_NEAR(gap.texel_value(0, x, y, k), expect, 0.5 * gap.units[std::size_t(k)]);
      }
  auto solid = synthetic_fabric(16, 2, 0.3, 0.2, /*gaps=*/false);
  EXPECT_TRUE(build_gap_tables(solid.inputs(), o).clusters.empty());
  auto all = build_radiance_tables(solid.inputs(), o);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].kind(), RadianceTableKind::Specular);
  EXPECT_EQ(build_radiance_tables(f.inputs(), o).size(), 2u);
}

TEST(RadianceFill, ClustersWithoutANonZeroTexelAreNotStored) {
  auto f = synthetic_fabric(16, 3, 0.3, 0.2, false);
  // Cluster 1 becomes pure gap: no specular table, a gap table; clusters 0, 2 the opposite.
  for (std::size_t t = 0; t < f.gap.size(); ++t)
    f.gap[t] = f.labels[t] == 1 ? 0.0f : 1.0f;
  RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  RadianceTableSet spec = build_specular_tables(f.inputs(), o);
  EXPECT_EQ(spec.clusters, (std::vector<uint32_t>{0, 2}));
  RadianceTableSet gap = build_gap_tables(f.inputs(), o);
  EXPECT_EQ(gap.clusters, (std::vector<uint32_t>{1}));
  // An unused cluster id (no texel at all) is not stored either.
  f.clusters = 5;
  EXPECT_EQ(build_specular_tables(f.inputs(), o).clusters, (std::vector<uint32_t>{0, 2}));
}

TEST(RadianceFill, BitIdenticalForAnyThreadCount) {
  auto f = synthetic_fabric(32, 4);
  RadianceOptions o;
  o.bins_per_side = 8;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  RadianceTableSet a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = build_specular_tables(f.inputs(), o);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = build_specular_tables(f.inputs(), o);
  }
  EXPECT_EQ(a.units, b.units);
  EXPECT_TRUE(a.sat == b.sat);
}

TEST(RadianceFill, WarnsWhenTheBinsCannotResolveTheNarrowestLobe) {
  auto f = synthetic_fabric(8, 1, 0.3, 0.01);
  RadianceOptions o;
  o.bins_per_side = 32;
  o.samples_per_side = 2;  // keep the test fast
  take_warnings();
  RadianceBuildReport report;
  build_specular_tables(f.inputs(), o, &report);
  EXPECT_FALSE(report.resolved);
  EXPECT_EQ(report.bins_needed, 126);
  auto warnings = take_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("radiance_dirs >= 126"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("0.01"), std::string::npos) << warnings[0];
  // Roughness 0.04 at 32^2 is resolved: no warning.
  auto satin = synthetic_fabric(8, 1, 0.04, 0.3);
  build_specular_tables(satin.inputs(), o, &report);
  EXPECT_TRUE(report.resolved);
  EXPECT_TRUE(take_warnings().empty());
}

TEST(RadianceFill, RejectsBadInputsNamingTheTexel) {
  RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;  // small test grids; the warning has its own test
  auto expect_error = [&](const tables_testing::SyntheticFabric& f, const std::string& needle) {
    try {
      build_specular_tables(f.inputs(), o);
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Input);
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  auto f = synthetic_fabric(8, 2);
  f.labels[9] = 2;
  expect_error(f, "texel (1, 1) has cluster label 2");
  f = synthetic_fabric(8, 2);
  f.gap[10] = 1.5f;
  expect_error(f, "texel (2, 1) has gap");
  f = synthetic_fabric(8, 2);
  f.yarn[3] = 7;
  expect_error(f, "texel (3, 0) has yarn id 7");
  f = synthetic_fabric(8, 2);
  f.tangent[4][1] = NAN;
  expect_error(f, "texel (4, 0) has a non-finite tangent");
  f = synthetic_fabric(8, 2);
  f.roughness[1] = 0.0;
  expect_error(f, "yarn 1 roughness");
  f = synthetic_fabric(8, 2);
  f.labels.pop_back();
  expect_error(f, "must all have 64 texels");
  o.bins_per_side = 0;
  expect_error(synthetic_fabric(8, 2), "radiance_dirs = 0");
}

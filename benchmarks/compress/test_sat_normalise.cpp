// The paper's SAT normalisation (benchmarks/compress/sat_normalise.hpp) and whole-SAT C-PCA layout
// (benchmarks/compress/sat_pca.hpp): study code, tested beside the study (docs/compression.md,
// "The paper's whole-SAT layout").
#include <gtest/gtest.h>

#include "benchmarks/compress/sat_pca.hpp"
#include "tests/support/compress_test_util.hpp"

namespace clothbake::compress {
namespace {

TEST(SatNormalise, ConstantTableIsExactlyThePlane) {
  const int n = 9;
  std::vector<float> table(n * n, 0.75f);
  std::vector<double> sat(n * n);
  summed_area_table(table.data(), n, sat.data());
  EXPECT_DOUBLE_EQ(sat[n * n - 1], 0.75 * n * n);
  std::vector<float> out(n * n);
  for (auto mode : {SatNormalisation::Plane, SatNormalisation::PlaneUnit}) {
    const SatTransform t = normalise_sat(sat.data(), n, mode, out.data());
    EXPECT_DOUBLE_EQ(t.mean, 0.75);
    for (int i = 0; i < n * n; ++i) {
      EXPECT_NEAR(out[std::size_t(i)], 0.0f, 1e-12);  // no deviation from the mean
      EXPECT_NEAR(t.restore(out[std::size_t(i)], i % n, i / n), sat[std::size_t(i)], 1e-9);
    }
    EXPECT_EQ(t.scale, 1.0);  // zero range: no division by zero
  }
}

TEST(SatNormalise, PlaneUnitMapsToTheUnitIntervalAndRestores) {
  const int n = 16;
  std::vector<float> table(n * n);
  for (int i = 0; i < n * n; ++i)
    table[std::size_t(i)] = float((i * 37) % 11) * 0.1f;
  std::vector<double> sat(n * n);
  summed_area_table(table.data(), n, sat.data());
  std::vector<float> out(n * n);
  const SatTransform t = normalise_sat(sat.data(), n, SatNormalisation::PlaneUnit, out.data());
  float lo = 1, hi = 0;
  for (float v : out) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_EQ(lo, 0.0f);
  EXPECT_NEAR(hi, 1.0f, 1e-7);
  for (int i = 0; i < n * n; ++i)
    EXPECT_NEAR(t.restore(out[std::size_t(i)], i % n, i / n), sat[std::size_t(i)],
                1e-5 * sat.back());
  // The deviation is what remains after the plane: the far corner has deviation 0.
  EXPECT_NEAR(t.restore(0.0, n - 1, n - 1) - t.offset, t.mean * n * n, 1e-9);
}

TEST(SatPca, FullRankModelAnswersLikeDirectSums) {
  const DirectionalTexels data = test::synthetic_texels(12, 2, 2, 1);
  for (auto mode : {SatNormalisation::None, SatNormalisation::PlaneUnit}) {
    SatPcaOptions o;
    o.clusters = 1;
    o.rank = 8;  // = number of tables (2 clusters x 4 bins): lossless up to fp16
    o.normalisation = mode;
    const SatPcaModel model = SatPcaModel::fit(data, o);
    // Float vectors: rounding only (SAT values up to ~300 unnormalised, ~1 normalised).
    EXPECT_LT(model.normalised_mse(), mode == SatNormalisation::None ? 1e-4 : 1e-6);
    const double h[3] = {0.3, -0.2, 0.9};
    for (const reader::Footprint r :
         {reader::Footprint{0, 0, 12, 12}, {1.5, 2.25, 6.5, 4.0}, {-3, -3, 20, 4}}) {
      const auto want = test::direct_sums(data.values, data.cluster, 12, 2, 2, r, h);
      for (int c = 0; c < 2; ++c) {
        double got = 0;
        ASSERT_TRUE(model.query(r, h, c, &got));
        EXPECT_NEAR(got, want[std::size_t(c)], 2e-3 * std::max(1.0, want[std::size_t(c)]));
      }
    }
  }
}

}  // namespace
}  // namespace clothbake::compress

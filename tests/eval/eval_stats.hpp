// Statistics the evaluator tests share: an opened asset, K estimates' mean and standard error, the
// exact reference, the comparisons within standard errors, and the direction pairs.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "eval/evaluator.hpp"

namespace clothbake::eval_test {

using eval::Estimate;
using eval::EvalOptions;
using eval::Evaluator;
using eval::Footprint;
using eval::kAllLobes;
using eval::LobeMask;
using eval::Method;
using eval::Rgb;
using eval::Rng;
using eval::Status;
using eval::TableChoice;

// An open asset and its evaluator (the evaluator keeps views into the asset).
struct Opened {
  reader::Asset asset;
  Evaluator evaluator;
};

inline std::unique_ptr<Opened> open(const std::string& path,
                                    TableChoice tables = TableChoice::Auto) {
  auto o = std::make_unique<Opened>();
  const Status s = o->asset.open_file(path.c_str());
  EXPECT_TRUE(s.ok()) << s.message();
  EvalOptions options;
  options.tables = tables;
  const Status e = o->evaluator.open(o->asset, options);
  EXPECT_TRUE(e.ok()) << e.message();
  return o;
}

struct Stats {
  Rgb mean, se;         // mean of K estimates and its standard error
  double sd_green = 0;  // standard deviation of one estimate (green)
};

inline Stats repeat(const Evaluator& ev, const Footprint& p, const double wi[3], const double wo[3],
                    Method method, uint32_t spp, int k, uint64_t seed, LobeMask mask = kAllLobes) {
  Rng rng(seed);
  Rgb sum, sum2;
  for (int i = 0; i < k; ++i) {
    Estimate e;
    const Status s = ev.estimate(p, wi, wo, method, spp, rng, mask, &e);
    EXPECT_TRUE(s.ok()) << s.message();
    sum += e.value;
    sum2 += e.value * e.value;
  }
  Stats st;
  st.mean = sum / double(k);
  for (int c = 0; c < 3; ++c) {
    const double var = std::max(0.0, sum2[c] / k - st.mean[c] * st.mean[c]) * k / (k - 1.0);
    (c == 0 ? st.se.r : c == 1 ? st.se.g : st.se.b) = std::sqrt(var / k);
    if (c == 1) st.sd_green = std::sqrt(var);
  }
  return st;
}

inline Rgb reference(const Evaluator& ev, const Footprint& p, const double wi[3],
                     const double wo[3], LobeMask mask = kAllLobes) {
  Rng rng(0);
  Estimate e;
  const Status s = ev.estimate(p, wi, wo, Method::Reference, 1, rng, mask, &e);
  EXPECT_TRUE(s.ok()) << s.message();
  return e.value;
}

// |mean - ref| within 3 standard errors per channel, plus `slack` relative to ref (table and float
// rounding that no number of samples removes).
inline void expect_within_3se(const Stats& st, const Rgb& ref, double slack,
                              const std::string& what) {
  for (int c = 0; c < 3; ++c)
    EXPECT_LE(std::abs(st.mean[c] - ref[c]), 3.0 * st.se[c] + slack * std::abs(ref[c]) + 1e-15)
        << what << " channel " << c << ": mean " << st.mean[c] << " reference " << ref[c] << " se "
        << st.se[c];
}

// The same for the channel mean: one comparison per case, so that a test of many cases at 3
// standard errors is not a test of the largest of many z-scores (48 channel comparisons would
// exceed 3 by chance with probability 12 %). The standard error of the channel mean is bounded by
// the mean of the channels' standard errors.
inline void expect_mean_within_3se(const Stats& st, const Rgb& ref, double slack,
                                   const std::string& what) {
  const double mean = st.mean.mean(), want = ref.mean(), se = st.se.mean();
  EXPECT_LE(std::abs(mean - want), 3.0 * se + slack * std::abs(want) + 1e-15)
      << what << ": mean " << mean << " reference " << want << " se <= " << se;
}

inline const double kReflectWi[3] = {0.3, 0.2, 0.9};
inline const double kReflectWo[3] = {-0.4, 0.1, 0.85};
inline const double kTransmitWi[3] = {0.2, -0.3, -0.8};  // light behind the cloth
inline const double kTransmitWo[3] = {-0.3, 0.1, 0.9};
struct Directions {
  const double* wi;
  const double* wo;
};
inline const Directions kConfigurations[] = {{kReflectWi, kReflectWo}, {kTransmitWi, kTransmitWo}};
}  // namespace clothbake::eval_test

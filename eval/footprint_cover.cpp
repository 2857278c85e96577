// The unbiased multi-scale estimate's cover of a footprint (footprint_cover.hpp).
#include "eval/footprint_cover.hpp"

#include <algorithm>
#include <cmath>

#include "eval/eval_data.hpp"

namespace clothbake::eval {

// The effective remainder of the form without a base: twice its area. Its residual f - g_V leaves
// the cheap samples of g_V most of the estimate's variance, so the cost-optimal count
// (remainder_samples) is about twice that of a g whose residual carries the rest (the goose-eye
// chair at 2 spp: relMSE 0.0081 -> 0.0044 for 0.047 -> 0.070 s; three times: 0.0033 in 0.095 s).
constexpr double kWithoutBaseRemainder = 2.0;

FootprintCover no_base_cover(const Footprint& p) noexcept {
  FootprintCover cover;
  cover.base = FootprintCover::Base::None;
  cover.regions[0].rect = p;
  cover.regions[0].area = (p.x1 - p.x0) * (p.y1 - p.y0);
  cover.region_count = 1;
  cover.remainder = kWithoutBaseRemainder;
  return cover;
}

PeriodBlock period_block(uint32_t n, const Footprint& p) noexcept {
  const double t = double(n);
  const double w = p.x1 - p.x0, h = p.y1 - p.y0;
  PeriodBlock best;
  double best_difference = INFINITY;
  for (const double kx : {std::max(1.0, std::floor(w / t)), std::max(1.0, std::ceil(w / t))})
    for (const double ky : {std::max(1.0, std::floor(h / t)), std::max(1.0, std::ceil(h / t))}) {
      // |A Δ P| = |A| + |P| − 2 |A ∩ P|, both anchored at the corner; ties keep the first pair.
      const double ax = kx * t, ay = ky * t;
      const double difference = ax * ay + w * h - 2.0 * std::min(ax, w) * std::min(ay, h);
      if (!(difference < best_difference)) continue;
      best_difference = difference;
      best.kx = kx;
      best.ky = ky;
    }
  const double ax = best.kx * t, ay = best.ky * t;
  const double inner_x = std::min(w, ax), inner_y = std::min(h, ay);
  // The column: P's part right of A (full height h) or A's part right of P (height ky N).
  const double column_height = w > ax ? h : ay;
  best.rects[0] = {p.x0 + inner_x, p.y0, p.x0 + std::max(w, ax), p.y0 + column_height};
  best.areas[0] = std::abs(w - ax) * column_height;
  best.signs[0] = w > ax ? 1.0 : -1.0;
  // The row: above the shorter of the two, over the narrower width.
  best.rects[1] = {p.x0, p.y0 + inner_y, p.x0 + inner_x, p.y0 + std::max(h, ay)};
  best.areas[1] = inner_x * std::abs(h - ay);
  best.signs[1] = h > ay ? 1.0 : -1.0;
  best.remainder = (best.areas[0] + best.areas[1]) / (w * h);
  return best;
}

double block_interior_spread(uint32_t rank, uint32_t full_rank) noexcept {
  if (rank >= full_rank) return 0.0;  // g_r is g: the interior has nothing left to sample
  // sqrt(var(g - g_r) / var(g)) at the sample's destination, rounded up from the medians over
  // random footprints and directions of the 256^2 example twill and satin, measured once with a
  // scratch program (docs/evaluator.md, "Footprints below a period"): it sets only the allocation
  // of cheap samples and the choice of the form, never the estimate's expectation.
  static constexpr double kSpread[4] = {0.4, 0.2, 0.12, 0.08};
  return kSpread[rank < 4 ? rank : 3];
}

namespace {

// What the block form's base costs beyond the whole-period form's, as a remainder fraction: three
// more prefix points of the bin's sums (about 0.4 us each on the 256^2 twill, bench_eval) are about
// 34 cheap samples (35 ns each), the samples of a remainder of 0.35 at kappa = 32 and 2 spp.
constexpr double kBlockBaseCost = 0.35;

// The whole-period form: the block and its two signed rectangles.
FootprintCover whole_periods(uint32_t n, const Footprint& p) {
  FootprintCover cover;
  cover.base = FootprintCover::Base::WholePeriods;
  cover.periods = period_block(n, p);
  for (int r = 0; r < 2; ++r) {
    CheapRegion& region = cover.regions[r];
    region.rect = cover.periods.rects[r];
    region.area = cover.periods.areas[r];
    region.sign = cover.periods.signs[r];
  }
  cover.region_count = 2;
  cover.remainder = cover.periods.remainder;
  return cover;
}

// The block form: A the block-aligned rectangle nearest to P (side B texels); no base when P
// rounds to no whole block.
FootprintCover blocks(const Footprint& p, double side, double interior_spread) {
  // Each edge to the nearest multiple of B (halves up): A in block units.
  const Footprint units{std::floor(p.x0 / side + 0.5), std::floor(p.y0 / side + 0.5),
                        std::floor(p.x1 / side + 0.5), std::floor(p.y1 / side + 0.5)};
  if (!(units.x1 > units.x0) || !(units.y1 > units.y0)) return no_base_cover(p);
  FootprintCover cover;
  const double area = (p.x1 - p.x0) * (p.y1 - p.y0);
  cover.base = FootprintCover::Base::Blocks;
  cover.blocks = units;
  const Footprint a{units.x0 * side, units.y0 * side, units.x1 * side, units.y1 * side};
  // The interior I = P ∩ A (never empty when A is not: each edge moved by at most B / 2) and the
  // box around P ∪ A.
  const Footprint in{std::max(p.x0, a.x0), std::max(p.y0, a.y0), std::min(p.x1, a.x1),
                     std::min(p.y1, a.y1)};
  const Footprint box{std::min(p.x0, a.x0), std::min(p.y0, a.y0), std::max(p.x1, a.x1),
                      std::max(p.y1, a.y1)};
  const double inner = (in.x1 - in.x0) * (in.y1 - in.y0);
  const double a_area = (a.x1 - a.x0) * (a.y1 - a.y0);
  uint32_t count = 0;
  auto add = [&](const Footprint& r, CheapRegion::Kind kind, double spread) {
    const double region_area = (r.x1 - r.x0) * (r.y1 - r.y0);
    if (!(region_area > 0.0)) return;
    CheapRegion& region = cover.regions[count++];
    region.rect = r;
    region.area = region_area;
    region.kind = kind;
    region.spread = spread;
  };
  if (interior_spread > 0.0) add(in, CheapRegion::Kind::Difference, interior_spread);
  // The strips: the box's columns left and right of I (full height), its rows below and above I.
  add({box.x0, box.y0, in.x0, box.y1}, CheapRegion::Kind::Indicator, 1.0);
  add({in.x1, box.y0, box.x1, box.y1}, CheapRegion::Kind::Indicator, 1.0);
  add({in.x0, box.y0, in.x1, in.y0}, CheapRegion::Kind::Indicator, 1.0);
  add({in.x0, in.y1, in.x1, box.y1}, CheapRegion::Kind::Indicator, 1.0);
  cover.region_count = count;
  // |A Δ P| = |A| + |P| - 2 |A ∩ P|.
  cover.remainder = (a_area + area - 2.0 * inner + interior_spread * inner) / area;
  return cover;
}

}  // namespace

FootprintCover cover_footprint(const EvalData& data, const Footprint& p) noexcept {
  const SubperiodSums& sums = data.subperiod;
  const FootprintBase form = data.options.footprint_base;
  const bool have_blocks = sums.is_open();
  const double side = have_blocks ? double(data.n / sums.blocks()) : 0.0;
  const double spread =
      have_blocks ? block_interior_spread(sums.layout().rank, data.visibility_rank()) : 0.0;
  switch (form) {
    case FootprintBase::WholePeriods:
      return whole_periods(data.n, p);
    case FootprintBase::Blocks:
      return have_blocks ? blocks(p, side, spread) : whole_periods(data.n, p);
    case FootprintBase::None:
      return no_base_cover(p);
    case FootprintBase::Auto:
      break;
  }
  // The form of least cost-weighted remainder: the whole-period form's, the block form's plus what
  // its base costs beyond one vector of sums (kBlockBaseCost: up to nine prefix points where the
  // whole-period form reads one), ties to the first; above EvalOptions::max_remainder_fraction the
  // form without a base, whose control variate g_V follows f more closely than any g with a base.
  FootprintCover best = whole_periods(data.n, p);
  double best_cost = best.remainder;
  if (have_blocks) {
    const FootprintCover b = blocks(p, side, spread);
    const double cost = b.remainder + kBlockBaseCost;
    if (b.base == FootprintCover::Base::Blocks && cost < best_cost) {
      best = b;
      best_cost = cost;
    }
  }
  if (best_cost > data.options.max_remainder_fraction) best = no_base_cover(p);
  return best;
}

uint32_t remainder_samples(const EvalData& data, const FootprintCover& cover,
                           uint32_t spp) noexcept {
  if (!(cover.remainder > 0.0)) return 0;
  // Cost-optimal: with a cost c0 per estimate, a per sample and c1 per cheap sample, the product of
  // the cost c0 + a spp + c1 m and the variance var(f - g) / spp + e^2 var(g) / m is least at
  // m = e sqrt(spp (c0 + a spp) var(g) / (c1 var(f - g))): linear in spp at high spp (so the
  // estimate converges at the Monte Carlo rate), about sqrt(spp) at low spp. c0 is about two
  // samples' cost (docs/evaluator.md, "Unbiased multi-scale").
  const double s = double(spp);
  const double m =
      std::ceil(data.options.remainder_sample_scale * cover.remainder * std::sqrt(s * (s + 2.0)));
  // At least one sample in each region that has an area: a region without a sample would drop
  // its integral.
  double pieces = 0.0;
  for (uint32_t r = 0; r < cover.region_count; ++r)
    pieces += double(cover.regions[r].area > 0.0);
  return uint32_t(std::clamp(m, std::max(1.0, pieces), double(kMaxRemainderSamples)));
}

void split_remainder_samples(const FootprintCover& cover, uint32_t m, uint32_t counts[5]) noexcept {
  for (int r = 0; r < 5; ++r)
    counts[r] = 0;
  if (m == 0) return;
  if (cover.base == FootprintCover::Base::WholePeriods) {
    // In proportion to the two rectangles' areas, each at least 1 when it has an area.
    const double* areas = cover.periods.areas;
    const double total = areas[0] + areas[1];
    uint32_t first = areas[1] > 0.0 ? uint32_t(std::lround(double(m) * areas[0] / total)) : m;
    if (areas[0] > 0.0 && first == 0) first = 1;
    if (areas[1] > 0.0 && first == m) first = m > 1 ? m - 1 : m;
    counts[0] = areas[0] > 0.0 ? first : 0;
    counts[1] = areas[1] > 0.0 ? m - first : 0;
    return;
  }
  // One per region, the rest in proportion to spread x area (largest remainders first, ties to the
  // first region): Neyman's allocation with the regions' relative spreads.
  const uint32_t regions = cover.region_count;
  double weight[5] = {}, total = 0.0;
  for (uint32_t r = 0; r < regions; ++r) {
    weight[r] = cover.regions[r].spread * cover.regions[r].area;
    total += weight[r];
    counts[r] = 1;
  }
  if (m <= regions || !(total > 0.0)) return;
  const uint32_t rest = m - regions;
  double fraction[5] = {};
  uint32_t given = 0;
  for (uint32_t r = 0; r < regions; ++r) {
    const double share = double(rest) * weight[r] / total;
    const uint32_t whole = uint32_t(std::floor(share));
    counts[r] += whole;
    given += whole;
    fraction[r] = share - double(whole);
  }
  while (given < rest) {
    uint32_t pick = 0;
    for (uint32_t r = 1; r < regions; ++r)
      if (fraction[r] > fraction[pick]) pick = r;
    ++counts[pick];
    fraction[pick] = -1.0;
    ++given;
  }
}

}  // namespace clothbake::eval

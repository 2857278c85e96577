// Block-mean parallax depths (parallax_blocks.hpp).
#include "eval/parallax_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <new>

namespace clothbake::eval {

bool ParallaxBlockMeans::init(const reader::ParallaxView* view, uint32_t n) noexcept {
  if (view == nullptr || !view->is_open() || n == 0) return false;
  const uint32_t bins = view->dirs() * view->dirs();
  try {
    once_.reset(new std::once_flag[bins]);
    sums_.assign(bins, FootprintSums());
    range_.assign(bins, 0.0);
  } catch (...) {
    return false;
  }
  view_ = view;
  n_ = n;
  block_ = n % 4 == 0 ? 4 : (n % 2 == 0 ? 2 : 1);
  blocks_ = n / block_;
  return true;
}

const FootprintSums* ParallaxBlockMeans::sums(uint32_t bin) const noexcept {
  if (bin >= sums_.size()) return nullptr;
  std::call_once(once_[bin], [&] {
    const uint32_t b = block_, nb = blocks_;
    const double inv = 1.0 / double(b * b);
    double lowest = INFINITY, highest = -INFINITY;  // over every texel (B divides N)
    try {
      sums_[bin].build(nb, 1, [&](uint64_t t, double* out) {
        const int64_t bx = int64_t(t % nb) * b, by = int64_t(t / nb) * b;
        double sum = 0.0;
        for (uint32_t y = 0; y < b; ++y)
          for (uint32_t x = 0; x < b; ++x) {
            const double r = view_->bin_depth(bin, bx + x, by + y);
            sum += r;
            lowest = std::min(lowest, r);
            highest = std::max(highest, r);
          }
        out[0] = sum * inv;
      });
    } catch (...) {
      // Left empty: the bin contributes depth 0.
    }
    if (!sums_[bin].empty()) range_[bin] = highest - lowest;
  });
  return sums_[bin].empty() ? nullptr : &sums_[bin];
}

double ParallaxBlockMeans::mean_depth(const reader::Footprint& p, const int bin[4],
                                      const double weight[4]) const noexcept {
  if (view_ == nullptr) return 0.0;
  const double b = double(block_);
  const reader::Footprint blocks{p.x0 / b, p.y0 / b, p.x1 / b, p.y1 / b};
  const double area = (blocks.x1 - blocks.x0) * (blocks.y1 - blocks.y0);
  reader::FootprintPlan plan;
  if (!(area > 0.0) || !reader::make_footprint_plan(blocks, blocks_, &plan)) return 0.0;
  double r = 0.0;
  for (int k = 0; k < 4; ++k) {
    if (!(weight[k] > 0.0) || bin[k] < 0) continue;
    const FootprintSums* table = sums(uint32_t(bin[k]));
    if (table == nullptr) continue;
    double integral = 0.0;
    table->integral(plan, 0, 1, &integral);
    r += weight[k] * (integral / area);
  }
  return r;
}

double ParallaxBlockMeans::depth_range(const int bin[4], const double weight[4]) const noexcept {
  if (view_ == nullptr) return 0.0;
  double range = 0.0;
  for (int k = 0; k < 4; ++k) {
    if (!(weight[k] > 0.0) || bin[k] < 0) continue;
    if (sums(uint32_t(bin[k])) != nullptr) range += weight[k] * range_[uint32_t(bin[k])];
  }
  return range;
}

}  // namespace clothbake::eval

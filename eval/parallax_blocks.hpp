// Block-mean parallax depths: the cheap footprint-constant shift of the unbiased multi-scale form
// (docs/evaluator.md, "Unbiased multi-scale", "The control variate's shift").
//
// The unbiased form moves its control variate by one constant offset per footprint, and any
// constant keeps it unbiased; the closer it is to the per-texel offsets of the footprint, the
// better the control variate correlates with the integrand. The paper's choice, the exact
// footprint mean from the parallax SATs (Sec. 5.2), reads 16 scattered points of a table of
// (N + 1)^2 x bins integers (270 MB at N = 256 with 32^2 bins). This reads 16 points of a small
// per-bin table instead: for each direction bin of the parallax table, the exclusive prefix sums
// (double) of the depth r averaged over blocks of B x B texels (B = 4 when 4 divides N, else 2 when
// N is even, else 1), built on the first footprint that needs the bin. The shift is Eq. 2 applied
// to the footprint integral of that block-constant depth, bilinear between the view's four bins as
// the per-texel depth is.
//
// Memory: (N/B + 1)^2 doubles per bin used, 34 KB at N = 256 (35 MB if all 1024 bins of a 32^2
// table are used). C++17, standard library only; thread-safe (a bin's table is built once, under
// std::call_once); mean_depth() does not allocate except on a bin's first use.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "eval/footprint_sums.hpp"
#include "formats/reader/parallax_sections.hpp"

namespace clothbake::eval {

class ParallaxBlockMeans {
 public:
  // Binds the tables to an open parallax view of resolution n (the view must outlive this). Returns
  // false when the per-bin bookkeeping cannot be allocated.
  bool init(const reader::ParallaxView* view, uint32_t n) noexcept;

  uint32_t block_size() const noexcept { return block_; }

  // The mean over footprint p (texel units, positive area, any position: the tile wraps) of the
  // block-constant depth, interpolated over the given direction bins of the parallax table (as
  // reader::ParallaxView::weighted_depth takes them), in tile-side units (<= 0). A bin whose table
  // cannot be allocated, or a footprint too large to plan, contributes depth 0 (still a valid
  // constant for the unbiased form).
  double mean_depth(const reader::Footprint& p, const int bin[4],
                    const double weight[4]) const noexcept;
  // The range (max - min) of the per-texel depth r over the tile, interpolated over the given bins
  // as mean_depth(), in tile-side units (>= 0): how far apart two texels' parallax offsets can be,
  // times the view's offset per unit depth. Builds a bin's table on its first use (0 for a bin
  // whose table cannot be allocated).
  double depth_range(const int bin[4], const double weight[4]) const noexcept;

 private:
  const FootprintSums* sums(uint32_t bin) const noexcept;

  const reader::ParallaxView* view_ = nullptr;
  uint32_t n_ = 0, block_ = 1, blocks_ = 0;
  mutable std::unique_ptr<std::once_flag[]> once_;
  mutable std::vector<FootprintSums> sums_;  // one per direction bin, empty until first use
  mutable std::vector<double> range_;        // per bin: max - min of the per-texel depth
};

}  // namespace clothbake::eval

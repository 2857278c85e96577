// How the unbiased multi-scale estimate covers a footprint P: a base region A whose integral of the
// control variate under the parallax push-forward is exact from tables, and the regions left to
// cheap samples of g (docs/evaluator.md, "Unbiased multi-scale", steps 3-4, and "Footprints below
// a period").
//
// Two bases:
//   whole periods  A = kx x ky whole tiles at P's corner (period_block); exact for the full control
//                  variate g from the bin's whole-tile push-forward sums (pushforward_sums.hpp);
//                  the rest of P is one or two signed rectangles of cheap samples of g.
//   blocks         A = the rectangle of whole source blocks (B = N / nb texels a side) nearest to
//                  P, each edge of P rounded to the nearest multiple of B; exact for the control
//                  variate at the block sums' visibility rank r, g_r, from the bin's block prefix
//                  sums (subperiod_sums.hpp). The rest is the interior I = P ∩ A, where the cheap
//                  samples take g - g_r (nothing when r is the full rank), and up to four strips of
//                  the box around P ∪ A outside I, where they take 1_P g - 1_A g_r:
//                    ∫_P g = ∫_A g_r + ∫_I (g - g_r) + Σ_strips ∫ (1_P g - 1_A g_r).
//                  A footprint that rounds to no block has A empty: no base.
// Each form with a base leaves an effective remainder e: the whole-period form |A Δ P| / |P|; the
// block form (|A Δ P| + σ_r |I|) / |P|, σ_r the spread of g - g_r relative to g's
// (kBlockInteriorSpread). The cover takes the form of the smaller e (whole periods on ties; the
// block form's e weighed with what its base costs beyond one vector of sums) and, where that
// exceeds EvalOptions::max_remainder_fraction, no base: the whole of P by cheap samples of g_V,
// the control variate with each texel's own visibility, fibre distribution and albedo. e also sets
// the number of cheap samples (remainder_samples).
//
// C++17, standard library only, no allocation. Safe on any finite footprint of positive area.
// Internal to the evaluator library.
#pragma once

#include <cstdint>

#include "eval/evaluator.hpp"

namespace clothbake::eval {

struct EvalData;

// The block A of whole periods the unbiased form integrates from its tables: kx by ky tiles at
// P's corner (x0, y0), each count ⌊w/N⌋ or ⌈w/N⌉ (and the same for h), at least 1, whichever pair
// makes the symmetric difference of A and P least. The rest of P is B = (P \ A) − (A \ P): at most
// two rectangles, the column between x0 + min(w, kx N) and x0 + max(w, kx N) and the row between
// y0 + min(h, ky N) and y0 + max(h, ky N) (over x0 .. x0 + min(w, kx N)), each added (+1) where P
// reaches beyond A and subtracted (−1) where A reaches beyond P, so that
//   ∫_P g = ∫_A g + Σ_r sign_r ∫_{rect_r} g.
struct PeriodBlock {
  double kx = 0, ky = 0;
  Footprint rects[2];        // the column, the row
  double areas[2] = {0, 0};  // 0 for a rectangle that is empty
  double signs[2] = {1, 1};
  double remainder = 0;  // (areas[0] + areas[1]) / |P|: |B| / |P|
};
PeriodBlock period_block(uint32_t n, const Footprint& footprint) noexcept;

// The relative spread σ_r of g - g_r against g's, by the block sums' visibility rank r below the
// control variate's full rank (docs/evaluator.md, "Footprints below a period"; the full rank has
// 0).
double block_interior_spread(uint32_t rank, uint32_t full_rank) noexcept;

// A region of cheap samples of g.
struct CheapRegion {
  enum class Kind : uint8_t {
    Signed,      // sign * g (the whole-period form's column and row; the whole of P without A)
    Difference,  // g - g_r (the block form's interior)
    Indicator,   // 1_P g - 1_A g_r (the block form's strips)
  };
  Footprint rect;
  double area = 0;
  double sign = 1;    // Signed only
  double spread = 1;  // the integrand's spread relative to g's: the allocation's weight
  Kind kind = Kind::Signed;
};

struct FootprintCover {
  enum class Base : uint8_t { WholePeriods, Blocks, None };
  Base base = Base::WholePeriods;
  PeriodBlock periods;  // WholePeriods: the block and its signed rectangles
  Footprint blocks;     // Blocks: A in block units (whole numbers; A in texels is B times this)
  CheapRegion regions[5];
  uint32_t region_count = 0;
  double remainder = 0;  // the effective remainder e of the form taken
};

// No base: the whole of P (positive area) as one region of cheap samples of g_V (effective
// remainder 2: footprint_cover.cpp, kWithoutBaseRemainder).
FootprintCover no_base_cover(const Footprint& footprint) noexcept;

// The cover of P (positive area) for `data`'s tables and options (EvalOptions::footprint_base):
// the whole-period form, the block form when the evaluator has block sums, or no base (above
// EvalOptions::max_remainder_fraction, or forced).
FootprintCover cover_footprint(const EvalData& data, const Footprint& footprint) noexcept;

inline constexpr uint32_t kMaxRemainderSamples = 1u << 16;
// The cheap samples of g the unbiased form draws over the cover's regions for spp samples:
// ⌈κ e √(spp (spp + 2))⌉ (κ = EvalOptions::remainder_sample_scale, e the cover's remainder), at
// least one per region with an area, at most kMaxRemainderSamples; 0 when nothing is left.
uint32_t remainder_samples(const EvalData& data, const FootprintCover& cover,
                           uint32_t spp) noexcept;

// How remainder_samples() cheap samples split over the cover's regions: counts[r] for region r
// (the whole-period form in proportion to the two rectangles' areas, each at least 1, as before
// the blocks; the block form one per region and the rest in proportion to spread x area, largest
// remainders first).
void split_remainder_samples(const FootprintCover& cover, uint32_t m, uint32_t counts[5]) noexcept;

}  // namespace clothbake::eval

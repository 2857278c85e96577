// Footprint queries on Integral-Radiance tables (paper Sec. 4.3, Eq. 8 and 11), independent of
// how the tables are stored: raw fixed-point SATs (formats/reader_raw/radiance_tables.hpp, the
// opt-in clothbake_reader_raw) or compressed ones
// (formats/reader/*compressed*) implement the same interface, so a renderer does not care which it
// has.
//
// What a query answers. A table is a piecewise-constant function of texel space: texel (x, y)
// holds T(x, y) on the unit square [x, x+1) x [y, y+1), repeated with period N in both directions
// (the tile wraps). For a footprint rectangle R = [x0, x1) x [y0, y1) in texel units (real
// corners; any size, from part of a texel to many tiles; anywhere, negative coordinates included)
//
//   F_c(R, h) = sum over the 4 half-vector bins b nearest to h (bilinear weights w_b between bin
//               centres, model/directions.hpp) of w_b * integral over R of T[c][b](x, y) dx dy,
//
// in texel^2 units (divide by the area (x1 - x0)(y1 - y0) for the footprint average, by N^2 for
// tile-uv units). A partially covered texel counts with its covered area: that is exactly what
// bilinear interpolation of the SAT between integer corners gives, so fractional corners are exact
// too. h is any non-zero direction in the local frame; it is folded to the upper hemisphere
// (D(h) = D(-h)) and need not be normalised. Tables with one bin (the gap table) ignore h.
//
// Cost: O(1) in the footprint size: a rectangle is reduced to one tile (FootprintPlan) and
// evaluated from at most 9 SAT points per bin (4 when it does not cross a tile edge).
//
// C++17, standard library only, noexcept, no allocation; safe for any argument values (bad ones
// give InvalidArgument) on tables that opened successfully.
#pragma once

#include <cstdint>

#include "formats/reader/radiance_layout.hpp"
#include "formats/reader/status.hpp"

namespace clothbake::reader {

// A footprint rectangle [x0, x1) x [y0, y1) in texel units (x1 >= x0, y1 >= y0).
struct Footprint {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// Widest footprint accepted, in tiles per axis (bounds every product; far beyond any pixel).
inline constexpr double kMaxFootprintTiles = 16777216.0;  // 2^24

// A footprint reduced to one tile of side N. With I(x, y) the integral of the periodic table over
// [0, x) x [0, y) for x, y in [0, N] (bilinear SAT lookups),
//   F = [I(rx1, ry1) - I(x0, ry1) - I(rx1, y0) + I(x0, y0)]
//     + qx [I(N, ry1) - I(N, y0)] + qy [I(rx1, N) - I(x0, N)] + qx qy I(N, N).
struct FootprintPlan {
  double x0 = 0, y0 = 0;    // in [0, N)
  double rx1 = 0, ry1 = 0;  // in [0, N]
  double qx = 0, qy = 0;    // whole tiles crossed (non-negative integers)
};

// Reduces `rect` to one tile of side n. InvalidArgument for non-finite corners, x1 < x0, y1 < y0,
// a footprint wider than kMaxFootprintTiles tiles or corners beyond 2^40 texels, or n == 0.
Status plan_footprint(const Footprint& rect, uint32_t n, FootprintPlan* out) noexcept;
// The same without a message (the hot path): false where plan_footprint fails.
bool make_footprint_plan(const Footprint& rect, uint32_t n, FootprintPlan* out) noexcept;

// Bilinear weights over at most 4 distinct half-vector bins (duplicates merged, zero weights
// dropped), for a grid of bins_per_side^2 bins on the folded upper hemisphere.
struct BinWeights {
  uint32_t count = 0;
  uint32_t bin[4] = {};
  double weight[4] = {};
};

// InvalidArgument for a zero or non-finite h, or bins_per_side == 0. bins_per_side == 1 gives the
// single bin with weight 1 for any h (even zero).
Status radiance_bin_weights(uint32_t bins_per_side, const double h[3], BinWeights* out) noexcept;
// The same without a message (the hot path).
bool make_bin_weights(uint32_t bins_per_side, const double h[3], BinWeights* out) noexcept;

// The query interface every table representation implements.
class RadianceTables {
 public:
  virtual ~RadianceTables() = default;

  virtual RadianceTableKind kind() const noexcept = 0;
  virtual uint32_t resolution() const noexcept = 0;     // N (0 while not open)
  virtual uint32_t bins_per_side() const noexcept = 0;  // n (1: no h dependence)
  // Clusters of the label map: query_all writes this many values; clusters without a stored table
  // answer 0.
  virtual uint32_t cluster_count() const noexcept = 0;

  // The hot path, which each representation implements: F_c(rect, h) for one cluster
  // c < cluster_count() (try_query) or for every cluster at once (try_query_all; out has
  // cluster_count() entries); false (out unspecified) on any bad argument, so that a renderer does
  // not pay for building messages (a Status carries a 320-byte buffer).
  virtual bool try_query(const Footprint& rect, const double h[3], uint32_t cluster,
                         double* out) const noexcept = 0;
  virtual bool try_query_all(const Footprint& rect, const double h[3],
                             double* out) const noexcept = 0;
  // Whether every bin of h's bilinear lookup is stored: false only for the tables of a
  // scene-planned asset at a bin that was left out; query() then says OutOfPlan.
  virtual bool covers_bins(const double h[3]) const noexcept {
    (void)h;
    return true;
  }

#ifndef CLOTHBAKE_SINGLE_FILE  // the single file makes no footprint queries
  // The same answers with a Status that says what was wrong: InvalidArgument naming the bad
  // argument (rect, h, cluster, null output) or "not open". One implementation for every
  // representation: the fast path, and only when it fails, the diagnosis.
  Status query(const Footprint& rect, const double h[3], uint32_t cluster,
               double* out) const noexcept;
  Status query_all(const Footprint& rect, const double h[3], double* out) const noexcept;

 private:
  // Why the fast path failed: the InvalidArgument Status (tables not open, null output, cluster
  // out of range when `cluster` is given, bad rect or h).
  Status diagnose(const Footprint& rect, const double h[3], const uint32_t* cluster,
                  const double* out) const noexcept;
#endif
};

}  // namespace clothbake::reader

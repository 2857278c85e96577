// The exact footprint average under the piecewise-constant texel model (exact_sum.hpp).
#include "eval/exact_sum.hpp"

#include <cmath>

namespace clothbake::eval {
namespace {

// The part [lo, hi) (offsets within the texel, 0 <= lo < hi <= 1) of texel `index` that an axis
// interval covers, `mult` times (the copies of one column index modulo N of a wide footprint).
struct AxisPiece {
  int64_t index;
  double lo, hi;
  double mult;
};

// The pieces of [a0, a1) (a1 > a0) on an axis of period n, calling emit(piece) for each; at most
// n + 2 pieces.
template <class Emit>
void axis_pieces(double a0, double a1, uint32_t n, Emit emit) {
  const double i0 = std::floor(a0);
  if (a1 <= i0 + 1.0) {  // inside one texel (a1 may be its right edge)
    emit(AxisPiece{int64_t(i0), a0 - i0, a1 - i0, 1.0});
    return;
  }
  double f0 = i0;  // first full column
  if (a0 > i0) {
    emit(AxisPiece{int64_t(i0), a0 - i0, 1.0, 1.0});
    f0 = i0 + 1.0;
  }
  const double f1 = std::floor(a1);  // full columns [f0, f1); f1 >= f0 since a1 > i0 + 1
  const double full = f1 - f0;
  if (full >= double(n)) {
    // Fold: column index m (mod n) appears q or q + 1 times.
    const double q = std::floor(full / double(n));
    const double r = full - q * double(n);
    const int64_t start = int64_t(f0);
    for (uint32_t m = 0; m < n; ++m) {
      // The k-th full column is start + k; its index modulo n is m for k = (m - start) mod n.
      int64_t k = (int64_t(m) - start) % int64_t(n);
      if (k < 0) k += n;
      emit(AxisPiece{int64_t(m), 0.0, 1.0, q + (double(k) < r ? 1.0 : 0.0)});
    }
  } else {
    for (double i = f0; i < f1; i += 1.0)
      emit(AxisPiece{int64_t(i), 0.0, 1.0, 1.0});
  }
  if (a1 > f1) emit(AxisPiece{int64_t(f1), 0.0, a1 - f1, 1.0});
}

double axis_piece_count(double a0, double a1, uint32_t n) {
  double count = 0.0;
  axis_pieces(a0, a1, n, [&](const AxisPiece&) { count += 1.0; });
  return count;
}

// Accumulates W(t); small footprints in a fixed array, large ones in a dense N x N map.
class WeightMap {
 public:
  explicit WeightMap(uint32_t n) : n_(n) {}
  bool make_dense(const model::Allocator* allocator) {
    return dense_.allocate(uint64_t(n_) * n_, allocator);
  }
  void add(uint64_t texel, double weight) {
    if (!dense_.empty()) {
      dense_[texel] += weight;
      return;
    }
    for (uint32_t k = 0; k < count_; ++k)
      if (texel_[k] == texel) {
        weight_[k] += weight;
        return;
      }
    texel_[count_] = texel;
    weight_[count_] = weight;
    ++count_;
  }
  template <class Visit>
  void for_each(Visit visit) const {
    if (!dense_.empty()) {
      for (uint64_t t = 0; t < dense_.size(); ++t)
        if (dense_[t] != 0.0) visit(t, dense_[t]);
      return;
    }
    for (uint32_t k = 0; k < count_; ++k)
      visit(texel_[k], weight_[k]);
  }

 private:
  static constexpr uint32_t kCapacity = kSmallExactSources * 16;  // 4 pieces x 4 view bins
  uint32_t n_;
  uint32_t count_ = 0;
  uint64_t texel_[kCapacity];
  double weight_[kCapacity];
  model::Buffer<double> dense_;
};

}  // namespace

double exact_source_count(const EvalData& data, const Footprint& p) noexcept {
  if (!(p.x1 > p.x0) || !(p.y1 > p.y0)) return 1.0;
  return axis_piece_count(p.x0, p.x1, data.n) * axis_piece_count(p.y0, p.y1, data.n);
}

Status exact_average(const EvalData& data, const ShadingFrame& frame, const Footprint& p,
                     uint32_t supersampling, Estimate* out) noexcept {
  TexelShading shading;
  const model::BinBilinear<double>& bins = frame.parallax_bins;
  if (!(p.x1 > p.x0) || !(p.y1 > p.y0)) {
    // A point: the integrand at x'_k(p0) of each view bin k, weighted.
    for (int k = 0; k < 4; ++k) {
      if (!(bins.weight[k] > 0.0)) continue;
      int64_t tx = 0, ty = 0;
      bin_destination(data, frame, k, p.x0, p.y0, &tx, &ty);
      shade_texel(data, frame, tx, ty, &shading);
      for (int l = 0; l < model::kLobeCount; ++l)
        out->lobes[l] += shading.lobes[l] * bins.weight[k];
      out->counters.texel_evals += 1;
    }
    return {};
  }

  WeightMap weights(data.n);
  const bool dense = supersampling > 0 || exact_source_count(data, p) > kSmallExactSources;
  if (dense && !weights.make_dense(data.allocator))
    return Status::error(reader::ErrorCode::Unsupported, reader::Check::None,
                         "reference: cannot allocate the %u x %u weight map", unsigned(data.n),
                         unsigned(data.n));

  axis_pieces(p.y0, p.y1, data.n, [&](const AxisPiece& py) {
    axis_pieces(p.x0, p.x1, data.n, [&](const AxisPiece& px) {
      for (int k = 0; k < 4; ++k) {
        if (!(bins.weight[k] > 0.0)) continue;
        const double mult = px.mult * py.mult * bins.weight[k];
        const double r = data.options.parallax
                             ? data.parallax.bin_depth(uint32_t(bins.index[k]), px.index, py.index)
                             : 0.0;
        const double dx = r * frame.bin_offset_per_depth[k][0];
        const double dy = r * frame.bin_offset_per_depth[k][1];
        const double x0 = double(px.index) + px.lo + dx, x1 = double(px.index) + px.hi + dx;
        const double y0 = double(py.index) + py.lo + dy, y1 = double(py.index) + py.hi + dy;
        if (supersampling > 0) {
          const double s = double(supersampling);
          const double cell = mult * (x1 - x0) * (y1 - y0) / (s * s);
          for (uint32_t b = 0; b < supersampling; ++b) {
            const double y = y0 + (double(b) + 0.5) / s * (y1 - y0);
            for (uint32_t a = 0; a < supersampling; ++a) {
              const double x = x0 + (double(a) + 0.5) / s * (x1 - x0);
              weights.add(data.texel(int64_t(std::floor(x)), int64_t(std::floor(y))), cell);
            }
          }
          continue;
        }
        // The moved piece is at most one texel wide: it overlaps columns c and c + 1, rows d, d
        // + 1.
        const double c = std::floor(x0), d = std::floor(y0);
        const double wx[2] = {std::fmin(x1, c + 1.0) - x0, x1 > c + 1.0 ? x1 - (c + 1.0) : 0.0};
        const double wy[2] = {std::fmin(y1, d + 1.0) - y0, y1 > d + 1.0 ? y1 - (d + 1.0) : 0.0};
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i)
            if (wx[i] > 0.0 && wy[j] > 0.0)
              weights.add(data.texel(int64_t(c) + i, int64_t(d) + j), mult * wx[i] * wy[j]);
      }
    });
  });

  const double area = (p.x1 - p.x0) * (p.y1 - p.y0);
  Rgb sums[model::kLobeCount];
  uint32_t evals = 0;
  weights.for_each([&](uint64_t t, double w) {
    shade_texel(data, frame, int64_t(t % data.n), int64_t(t / data.n), &shading);
    for (int l = 0; l < model::kLobeCount; ++l)
      sums[l] += shading.lobes[l] * w;
    ++evals;
  });
  for (int l = 0; l < model::kLobeCount; ++l)
    out->lobes[l] += sums[l] / area;
  out->counters.texel_evals += evals;
  return {};
}

}  // namespace clothbake::eval

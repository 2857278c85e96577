// Whole-tile push-forward sums per parallax view bin (pushforward_sums.hpp).
#include "eval/pushforward_sums.hpp"

#include <cmath>

#include "eval/eval_data.hpp"
#include "model/directions.hpp"

namespace clothbake::eval {

bool PushforwardSums::init(const EvalData* data, uint32_t bins,
                           const PushforwardChannels& layout) noexcept {
  data_ = data;
  layout_ = layout;
  return once_.allocate(bins, data->allocator) && sums_.allocate(bins, data->allocator);
}

const double* PushforwardSums::bin_sums(uint32_t bin) const noexcept {
  if (bin >= sums_.size()) return nullptr;
  std::call_once(once_[bin], [&] { build(bin); });
  return sums_[bin].empty() ? nullptr : sums_[bin].data();
}

void PushforwardSums::build(uint32_t bin) const noexcept {
  const EvalData& d = *data_;
  const uint32_t n = d.n;
  const uint64_t texels = uint64_t(n) * n;
  model::Buffer<double> multiplicity, sums;  // zero-filled
  if (!multiplicity.allocate(texels, d.allocator) || !sums.allocate(layout_.count(), d.allocator))
    return;  // bin_sums() answers null
  // m_k: every source texel's unit square moved rigidly by its bin depth at the bin's centre.
  double factor[2];
  d.bin_offset_per_depth(bin, factor);
  for (uint32_t qy = 0; qy < n; ++qy)
    for (uint32_t qx = 0; qx < n; ++qx) {
      const double r = d.options.parallax ? d.parallax.bin_depth(bin, qx, qy) : 0.0;
      const double x = double(qx) + r * factor[0], y = double(qy) + r * factor[1];
      const double fx = std::floor(x), fy = std::floor(y);
      const double ax = x - fx, ay = y - fy;
      const int64_t cx = int64_t(fx), cy = int64_t(fy);
      multiplicity[d.texel(cx, cy)] += (1.0 - ax) * (1.0 - ay);
      multiplicity[d.texel(cx + 1, cy)] += ax * (1.0 - ay);
      multiplicity[d.texel(cx, cy + 1)] += (1.0 - ax) * ay;
      multiplicity[d.texel(cx + 1, cy + 1)] += ax * ay;
    }
  // S_k = sum_t m_k(t) channels(t).
  const uint32_t m = layout_.rank;
  double e[17];
  double weights[reader::kMaxCompressedRank + 1];
  for (uint64_t t = 0; t < texels; ++t) {
    const double w = multiplicity[t];
    if (w == 0.0) continue;
    const uint32_t x = uint32_t(t % n), y = uint32_t(t / n);
    d.visibility_coefficients(t, e);
    uint32_t first = 0;
    const uint32_t count = d.specular.compressed.texel_image_weights(x, y, &first, weights);
    for (uint32_t i = 0; i < count; ++i) {
      const double wi = w * weights[i];
      if (wi == 0.0) continue;
      double* s = &sums[layout_.spec(first + i, 0)];
      for (uint32_t j = 0; j <= m; ++j)
        s[j] += wi * e[j];
    }
    const uint32_t c = d.clusters.label(x, y);
    const YarnShading& yarn = d.yarns[d.maps.yarn_id[t]];
    const float* colour = d.maps.albedo.data + 3 * t;
    const double gap = d.maps.gap[t];
    double value[PushforwardChannels::kPerLobeGroup];
    for (int ch = 0; ch < 3; ++ch) {
      value[ch] = gap * yarn.diffuse_reflectance[ch] * double(colour[ch]);
      value[3 + ch] = gap * yarn.diffuse_transmittance[ch] * double(colour[ch]);
    }
    value[6] = 1.0;
    value[7] = 1.0 - gap;
    for (uint32_t j = 0; j <= m; ++j) {
      double* s = &sums[layout_.lobe(c, j)];
      const double we = w * e[j];
      for (uint32_t q = 0; q < PushforwardChannels::kPerLobeGroup; ++q)
        s[q] += we * value[q];
    }
  }
  sums_[bin] = std::move(sums);
}

}  // namespace clothbake::eval

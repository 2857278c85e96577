// Block push-forward sums per parallax view bin (subperiod_sums.hpp).
#include "eval/subperiod_sums.hpp"

#include <cmath>

#include "eval/eval_data.hpp"
#include "model/directions.hpp"

namespace clothbake::eval {

bool SubperiodSums::init(const EvalData* data, uint32_t bins, const PushforwardChannels& layout,
                         uint32_t blocks) noexcept {
  data_ = data;
  layout_ = layout;
  blocks_ = 0;
  if (!once_.allocate(bins, data->allocator) || !prefix_.allocate(bins, data->allocator))
    return false;
  blocks_ = blocks;
  return true;
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
uint64_t SubperiodSums::bin_bytes() const noexcept {
  return uint64_t(blocks_ + 1) * (blocks_ + 1) * layout_.count() * sizeof(float);
}
#endif

const float* SubperiodSums::bin_prefix(uint32_t bin) const noexcept {
  if (bin >= prefix_.size()) return nullptr;
  std::call_once(once_[bin], [&] { build(bin); });
  return prefix_[bin].empty() ? nullptr : prefix_[bin].data();
}

void SubperiodSums::build(uint32_t bin) const noexcept {
  const EvalData& d = *data_;
  const uint32_t n = d.n, nb = blocks_, side = n / nb;
  const uint32_t count = layout_.count(), rank = layout_.rank;
  const uint64_t points = uint64_t(nb + 1) * (nb + 1);
  model::Buffer<double> prefix, block;  // zero-filled
  if (!prefix.allocate(points * count, d.allocator) || !block.allocate(count, d.allocator))
    return;  // bin_prefix() answers null
  double factor[2];
  d.bin_offset_per_depth(bin, factor);
  const ControlVariateTexels& records = d.cv_texels;
  // Adds weight * channels(t) at rank r: the same per-texel values the control variate reads
  // (the record's cell images and stored weights, visibility coefficients, gap, colour, yarn).
  auto splat = [&](uint64_t t, double weight) {
    const ControlVariateTexels::Header& texel = records.header(t);
    double e[reader::kMaxVisibilityBasisRank + 1];
    e[0] = weight;
    const float* coefficients = records.coefficients(t);
    for (uint32_t j = 0; j < rank; ++j)
      e[j + 1] = weight * double(coefficients[j]);
    if (texel.count > 0) {
      const int16_t* q = records.image_weights(t);
      for (uint32_t i = 0; i < texel.count; ++i) {
        const double w = i == 0 ? 1.0 : double(q[i - 1]);
        double* s = &block[layout_.spec(texel.first_image + i, 0)];
        for (uint32_t j = 0; j <= rank; ++j)
          s[j] += w * e[j];
      }
    }
    const YarnShading& yarn = d.yarns[texel.yarn];
    const double gap = texel.gap;
    double value[PushforwardChannels::kPerLobeGroup];
    for (int ch = 0; ch < 3; ++ch) {
      value[ch] = gap * yarn.diffuse_reflectance[ch] * double(texel.colour[ch]);
      value[3 + ch] = gap * yarn.diffuse_transmittance[ch] * double(texel.colour[ch]);
    }
    value[6] = 1.0;
    value[7] = 1.0 - gap;
    for (uint32_t j = 0; j <= rank; ++j) {
      double* s = &block[layout_.lobe(texel.label, j)];
      for (uint32_t q = 0; q < PushforwardChannels::kPerLobeGroup; ++q)
        s[q] += e[j] * value[q];
    }
  };
  for (uint32_t by = 0; by < nb; ++by)
    for (uint32_t bx = 0; bx < nb; ++bx) {
      for (double& b : block)
        b = 0.0;
      for (uint32_t qy = by * side; qy < (by + 1) * side; ++qy)
        for (uint32_t qx = bx * side; qx < (bx + 1) * side; ++qx) {
          const double r = d.options.parallax ? d.parallax.bin_depth(bin, qx, qy) : 0.0;
          const double x = double(qx) + r * factor[0], y = double(qy) + r * factor[1];
          const double fx = std::floor(x), fy = std::floor(y);
          const double ax = x - fx, ay = y - fy;
          const int64_t cx = int64_t(fx), cy = int64_t(fy);
          splat(d.texel(cx, cy), (1.0 - ax) * (1.0 - ay));
          if (ax > 0.0) splat(d.texel(cx + 1, cy), ax * (1.0 - ay));
          if (ay > 0.0) splat(d.texel(cx, cy + 1), (1.0 - ax) * ay);
          if (ax > 0.0 && ay > 0.0) splat(d.texel(cx + 1, cy + 1), ax * ay);
        }
      // prefix(bx + 1, by + 1) = block + prefix(bx, by + 1) + prefix(bx + 1, by) - prefix(bx, by)
      double* out = &prefix[(uint64_t(by + 1) * (nb + 1) + bx + 1) * count];
      const double* left = &prefix[(uint64_t(by + 1) * (nb + 1) + bx) * count];
      const double* below = &prefix[(uint64_t(by) * (nb + 1) + bx + 1) * count];
      const double* corner = &prefix[(uint64_t(by) * (nb + 1) + bx) * count];
      for (uint32_t c = 0; c < count; ++c)
        out[c] = block[c] + left[c] + below[c] - corner[c];
    }
  model::Buffer<float> stored;
  if (!stored.allocate(prefix.size(), d.allocator)) return;
  for (std::size_t i = 0; i < prefix.size(); ++i)
    stored[i] = float(prefix[i]);
  prefix_[bin] = std::move(stored);
}

}  // namespace clothbake::eval

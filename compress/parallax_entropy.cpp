// The block coder's encoder (parallax_entropy.hpp).
#include "compress/parallax_entropy.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/error.hpp"
#include "formats/reader/parallax_entropy.hpp"

namespace clothbake::compress {
namespace {

using reader::kEntropyContexts;
using reader::kRansLow;
using reader::kRansScale;
using reader::kRansScaleBits;

void put16(std::vector<uint8_t>& out, uint32_t v) {
  out.push_back(uint8_t(v));
  out.push_back(uint8_t(v >> 8));
}

}  // namespace

void normalise_frequencies(const uint64_t* counts, uint16_t* freq) {
  uint64_t total = 0;
  for (int s = 0; s < 256; ++s)
    total += counts[s];
  std::memset(freq, 0, 256 * sizeof(uint16_t));
  if (total == 0) return;
  int64_t sum = 0;
  for (int s = 0; s < 256; ++s)
    if (counts[s] > 0) {
      const uint64_t f = (counts[s] * kRansScale + total / 2) / total;
      freq[s] = uint16_t(std::max<uint64_t>(1, std::min<uint64_t>(f, kRansScale)));
      sum += freq[s];
    }
  while (sum != int64_t(kRansScale)) {  // adjust the largest frequency (ties: lowest symbol)
    int best = 0;
    for (int s = 1; s < 256; ++s)
      if (freq[s] > freq[best]) best = s;
    if (sum > int64_t(kRansScale)) {
      if (freq[best] <= 1) break;  // cannot happen: at most 256 symbols of frequency 1
      --freq[best];
      --sum;
    } else {
      ++freq[best];
      ++sum;
    }
  }
}

void rans_encode_block(uint32_t sx, uint32_t sy, uint32_t group, const uint8_t* ctx,
                       const uint8_t* sym, std::size_t count, const uint16_t* freq,
                       std::vector<uint8_t>& out) {
  const int contexts = 1 + *std::max_element(ctx, ctx + std::max<std::size_t>(count, 1));
  std::vector<uint16_t> start(std::size_t(std::max(contexts, 1)) * 256);
  for (int c = 0; c < contexts; ++c) {
    uint32_t total = 0;
    for (int s = 0; s < 256; ++s) {
      start[std::size_t(c) * 256 + s] = uint16_t(total);
      total += freq[c * 256 + s];
    }
  }
  out.reserve(out.size() + 12 + count / 4);
  put16(out, sx);
  put16(out, sy);
  put16(out, group);
  put16(out, 0);  // flags
  // rANS, symbols in reverse; the decoder reads the final state, then the bytes backwards.
  std::vector<uint8_t> emitted;
  emitted.reserve(count / 4);
  uint32_t x = kRansLow;
  for (std::size_t i = count; i-- > 0;) {
    const std::size_t k = std::size_t(ctx[i]) * 256 + sym[i];
    const uint32_t f = freq[k], st = start[k];
    if (f == 0) throw_internal_error("rans_encode_block: a symbol without a frequency");
    const uint32_t x_max = ((kRansLow >> kRansScaleBits) << 8) * f;
    while (x >= x_max) {
      emitted.push_back(uint8_t(x));
      x >>= 8;
    }
    x = ((x / f) << kRansScaleBits) + (x % f) + st;
  }
  for (int k = 0; k < 4; ++k)
    out.push_back(uint8_t(x >> (8 * k)));
  out.insert(out.end(), emitted.rbegin(), emitted.rend());
}

std::vector<uint64_t> parallax_residual_counts(const uint8_t* plane, uint32_t n, uint32_t sx,
                                               uint32_t sy) {
  std::vector<uint64_t> counts(std::size_t(kEntropyContexts) * 256, 0);
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const reader::EntropyPrediction p = reader::predict_parallax_code(plane, n, x, y, sx, sy);
      ++counts[std::size_t(p.context) * 256 + uint8_t(plane[uint64_t(y) * n + x] - p.value)];
    }
  return counts;
}

std::vector<uint16_t> parallax_frequencies(const std::vector<uint64_t>& counts) {
  std::vector<uint16_t> freq(std::size_t(kEntropyContexts) * 256, 0);
  for (int c = 0; c < kEntropyContexts; ++c)
    normalise_frequencies(counts.data() + std::size_t(c) * 256, freq.data() + std::size_t(c) * 256);
  return freq;
}

std::vector<uint8_t> encode_parallax_block(const uint8_t* plane, uint32_t n, uint32_t sx,
                                           uint32_t sy, uint32_t group, const uint16_t* freq) {
  const uint64_t count = uint64_t(n) * n;
  std::vector<uint8_t> ctx(count), sym(count);
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const reader::EntropyPrediction p = reader::predict_parallax_code(plane, n, x, y, sx, sy);
      const uint64_t i = uint64_t(y) * n + x;
      ctx[i] = uint8_t(p.context);
      sym[i] = uint8_t(plane[i] - p.value);
    }
  std::vector<uint8_t> out;
  rans_encode_block(sx, sy, group, ctx.data(), sym.data(), count, freq, out);
  return out;
}

std::vector<std::pair<uint32_t, uint32_t>> parallax_shift_candidates(const uint8_t* plane,
                                                                     uint32_t n, int count,
                                                                     uint32_t min_length) {
  const uint32_t samples = std::min<uint32_t>(n, 64), sample_step = std::max<uint32_t>(1, n / 64);
  const uint32_t shift_step = std::max<uint32_t>(1, n / 256);
  struct Scored {
    double score;
    uint32_t sx, sy;
  };
  // Every shift is scored on the same samples; rows of shifts in parallel, concatenated in order
  // (the same list as a serial scan, so the same candidates for any thread count).
  std::vector<uint8_t> sampled(std::size_t(samples) * samples);
  for (uint32_t j = 0; j < samples; ++j)
    for (uint32_t i = 0; i < samples; ++i)
      sampled[std::size_t(j) * samples + i] =
          plane[uint64_t(j * sample_step) * n + uint64_t(i * sample_step)];
  const uint32_t shift_rows = (n + shift_step - 1) / shift_step;
  std::vector<std::vector<Scored>> rows(shift_rows);
  tbb::parallel_for(uint32_t(0), shift_rows, [&](uint32_t row) {
    const uint32_t sy = row * shift_step;
    // The sample (i, j) shifted by (sx, sy) reads source row r_j = (j step + n - sy) mod n at
    // column (i step + n - sx) mod n = n - sx + i step of the row repeated twice. Split the
    // repeated row by the column's residue modulo the step, so that the samples of every shift are
    // a contiguous window: decimated[r_j][res][q + i] with n - sx = res + q step. The same
    // comparisons as sampling each shift directly, in a loop the compiler vectorises.
    const uint32_t length = (2 * n + sample_step - 1) / sample_step;
    std::vector<uint8_t> decimated(std::size_t(samples) * sample_step * length);
    auto window = [&](uint32_t j, uint32_t residue) {
      return decimated.data() + (std::size_t(j) * sample_step + residue) * length;
    };
    for (uint32_t j = 0; j < samples; ++j) {
      const uint8_t* source = plane + uint64_t((j * sample_step + n - sy) % n) * n;
      for (uint32_t residue = 0; residue < sample_step; ++residue) {
        uint8_t* out = window(j, residue);
        for (uint32_t q = 0; q < length; ++q) {
          const uint64_t column = uint64_t(residue) + uint64_t(q) * sample_step;
          out[q] = column < 2 * uint64_t(n) ? source[column % n] : 0;
        }
      }
    }
    for (uint32_t sx = 0; sx < n; sx += shift_step) {
      if (sx == 0 && sy == 0) continue;
      if (std::max(std::min(sx, n - sx), std::min(sy, n - sy)) < min_length) continue;
      const uint32_t start = n - sx, residue = start % sample_step, q = start / sample_step;
      uint32_t match = 0;
      for (uint32_t j = 0; j < samples; ++j) {
        const uint8_t* own = sampled.data() + std::size_t(j) * samples;
        const uint8_t* other = window(j, residue) + q;
        uint32_t row_match = 0;
        for (uint32_t i = 0; i < samples; ++i)
          row_match += own[i] == other[i] ? 1u : 0u;
        match += row_match;
      }
      const double share = double(match) / double(samples * samples);
      if (share < 0.5) continue;
      const double causal = sy > 0 ? double(n - sy) / n : double(n - sx) / n;
      rows[row].push_back({share * causal, sx, sy});
    }
  });
  std::vector<Scored> scored;
  for (const auto& r : rows)
    scored.insert(scored.end(), r.begin(), r.end());
  std::stable_sort(scored.begin(), scored.end(),
                   [](const Scored& a, const Scored& b) { return a.score > b.score; });
  std::vector<std::pair<uint32_t, uint32_t>> out;
  for (const Scored& s : scored) {
    if (int(out.size()) >= count) break;
    out.push_back({s.sx, s.sy});
  }
  return out;
}

double residual_entropy_bits(const std::vector<uint64_t>& counts) {
  double bits = 0.0;
  for (std::size_t c = 0; c < counts.size() / 256; ++c) {
    uint64_t total = 0;
    for (int s = 0; s < 256; ++s)
      total += counts[std::size_t(c) * 256 + s];
    for (int s = 0; s < 256; ++s)
      if (const uint64_t k = counts[std::size_t(c) * 256 + s])
        bits -= double(k) * std::log2(double(k) / double(total));
  }
  return bits;
}

}  // namespace clothbake::compress

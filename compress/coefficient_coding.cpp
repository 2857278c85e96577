// Entropy-coded C-PCA coefficients: the encoder (coefficient_coding.hpp).
#include "compress/coefficient_coding.hpp"

#include <algorithm>
#include <cstring>

#include "common/error.hpp"
#include "compress/parallax_entropy.hpp"
#include "formats/reader/compressed_coefficients.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress {
namespace {

using reader::kCoefficientContexts;
using reader::kCoefficientSymbols;
using reader::kRansLow;
using reader::kRansScale;
using reader::kRansScaleBits;

// One coded symbol: a bit length in its context, or a uniform chunk of k bits.
struct Symbol {
  uint32_t start, freq;
};

void put(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int k = 0; k < bytes; ++k)
    out.push_back(uint8_t(value >> (8 * k)));
}

}  // namespace

std::vector<uint8_t> encode_compressed_coefficients(const CompressedTableSet& set, uint32_t sx,
                                                    uint32_t sy) {
  const uint32_t n = set.info.resolution;
  const uint64_t texels = uint64_t(n) * n;
  if (set.cell_map.size() != texels)
    throw_internal_error("coefficient coding: the cell map is not N x N");
  std::vector<uint32_t> first(texels), ranks(set.cells.size());
  for (std::size_t g = 0; g < set.cells.size(); ++g)
    ranks[g] = set.cells[g].rank;
  uint64_t next = 0;
  for (uint64_t t = 0; t < texels; ++t) {
    first[t] = uint32_t(next);
    const uint8_t g = set.cell_map[t];
    if (g != reader::kNoCell) next += ranks.at(g);
  }
  if (next != set.coefficients.size())
    throw_internal_error("coefficient coding: the cells hold another number of coefficients");
  // Pass 1: contexts and bit lengths; counts per context.
  std::vector<uint8_t> context(next), length(next);
  std::vector<uint32_t> zigzag(next);
  std::vector<uint64_t> counts(std::size_t(kCoefficientContexts) * 256, 0);
  {
    uint64_t k = 0;
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) {
        const uint8_t g = set.cell_map[uint64_t(y) * n + x];
        if (g == reader::kNoCell) continue;
        for (uint32_t j = 0; j < ranks[g]; ++j, ++k) {
          const reader::CoefficientPrediction p = reader::predict_coefficient(
              set.coefficients.data(), first.data(), set.cell_map.data(), n, x, y, j, sx, sy);
          const int32_t r = int32_t(set.coefficients[k]) - p.value;
          const uint32_t z = r >= 0 ? uint32_t(2 * r) : uint32_t(-2 * int64_t(r) - 1);
          uint32_t b = 0;
          while ((z >> b) != 0)
            ++b;
          context[k] = uint8_t(p.context);
          length[k] = uint8_t(b);
          zigzag[k] = z;
          ++counts[std::size_t(p.context) * 256 + b];
        }
      }
  }
  std::vector<uint16_t> freq(std::size_t(kCoefficientContexts) * kCoefficientSymbols, 0);
  for (uint32_t c = 0; c < kCoefficientContexts; ++c) {
    uint16_t full[256];
    normalise_frequencies(counts.data() + std::size_t(c) * 256, full);
    std::copy(full, full + kCoefficientSymbols,
              freq.begin() + std::ptrdiff_t(c) * kCoefficientSymbols);
  }
  std::vector<uint16_t> start(freq.size(), 0);
  for (uint32_t c = 0; c < kCoefficientContexts; ++c) {
    uint32_t total = 0;
    for (uint32_t s = 0; s < kCoefficientSymbols; ++s) {
      start[c * kCoefficientSymbols + s] = uint16_t(total);
      total += freq[c * kCoefficientSymbols + s];
    }
  }
  // Pass 2: the symbols in decoding order, then rANS in reverse.
  std::vector<Symbol> symbols;
  symbols.reserve(next * 2);
  for (uint64_t k = 0; k < next; ++k) {
    const std::size_t row = std::size_t(context[k]) * kCoefficientSymbols + length[k];
    symbols.push_back({start[row], freq[row]});
    for (uint32_t left = length[k] > 0 ? length[k] - 1u : 0u; left > 0;) {
      const uint32_t bits = std::min<uint32_t>(left, 8);
      left -= bits;
      const uint32_t v = (zigzag[k] >> left) & ((1u << bits) - 1);
      symbols.push_back({v << (kRansScaleBits - bits), kRansScale >> bits});
    }
  }
  std::vector<uint8_t> emitted;
  emitted.reserve(symbols.size() / 2);
  uint32_t x = kRansLow;
  for (std::size_t i = symbols.size(); i-- > 0;) {
    const uint32_t f = symbols[i].freq;
    if (f == 0) throw_internal_error("coefficient coding: a symbol without a frequency");
    const uint32_t x_max = ((kRansLow >> kRansScaleBits) << 8) * f;
    while (x >= x_max) {
      emitted.push_back(uint8_t(x));
      x >>= 8;
    }
    x = ((x / f) << kRansScaleBits) + (x % f) + symbols[i].start;
  }
  std::vector<uint8_t> out;
  out.reserve(reader::kCoefficientHeaderBytes + reader::kCoefficientTableBytes + emitted.size());
  put(out, next, 4);
  put(out, sx, 2);
  put(out, sy, 2);
  put(out, kCoefficientContexts, 4);
  put(out, x, 4);
  for (uint16_t f : freq)
    put(out, f, 2);
  out.insert(out.end(), emitted.rbegin(), emitted.rend());
  return out;
}

std::vector<uint8_t> code_compressed_coefficients(const CompressedTableSet& set) {
  const uint32_t n = set.info.resolution;
  std::vector<uint8_t> best = encode_compressed_coefficients(set, 0, 0);
  // The tile's repeats, from a fingerprint of each texel's cell and coefficients (the cell map
  // alone, piecewise constant, repeats almost anywhere at short shifts).
  const uint64_t texels = uint64_t(n) * n;
  std::vector<uint8_t> fingerprint(texels, 0);
  for (uint64_t t = 0, next = 0; t < texels; ++t) {
    const uint8_t g = set.cell_map[t];
    if (g == reader::kNoCell) continue;
    uint32_t h = 2166136261u ^ g;  // FNV-1a over the cell and its coefficients
    for (uint32_t j = 0; j < set.cells[g].rank; ++j)
      h = (h ^ uint16_t(set.coefficients[next + j])) * 16777619u;
    next += set.cells[g].rank;
    fingerprint[t] = uint8_t(h ^ (h >> 8) ^ (h >> 16) ^ (h >> 24));
  }
  for (const auto& [sx, sy] :
       parallax_shift_candidates(fingerprint.data(), n, 3, std::max<uint32_t>(4, n / 16))) {
    std::vector<uint8_t> coded = encode_compressed_coefficients(set, sx, sy);
    if (coded.size() < best.size()) best = std::move(coded);
  }
  return best;
}

}  // namespace clothbake::compress

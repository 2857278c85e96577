// Hierarchical parallax: quantisation and coding (parallax_hierarchy.hpp).
#include "compress/parallax_hierarchy.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "common/error.hpp"
#include "compress/parallax_entropy.hpp"
#include "formats/reader/parallax_hierarchy.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress {
namespace {

using reader::kHierContexts;

constexpr int kMaxQuantisationRounds = 6;
constexpr double kStepMargin = 0.98;

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Steps and weights for the target `scale` (texels of RMS error asked of every direction).
void make_steps(HierarchicalParallax& p, const std::vector<double>& per_depth_eff, double range,
                double scale) {
  const std::size_t d = per_depth_eff.size();
  p.steps.assign(d, 0.0);
  p.weights.assign(d, 1);
  if (!(range > 0.0)) return;  // a flat table: step 0, every code 0
  const double finest = range / 65535.0, coarsest = std::min(range, 1.0);
  for (std::size_t e = 0; e < d; ++e) {
    const double t = per_depth_eff[e];
    const double step = t > 0.0 ? std::sqrt(12.0) * scale / t : coarsest;
    p.steps[e] = std::clamp(step, finest, coarsest);
  }
  const double lo = *std::min_element(p.steps.begin(), p.steps.end());
  const double hi = *std::max_element(p.steps.begin(), p.steps.end());
  const double unit = std::max(lo / 1024.0, hi / double(reader::kMaxHierWeight));
  for (std::size_t e = 0; e < d; ++e) {
    const double m =
        std::clamp(std::nearbyint(p.steps[e] / unit), 1.0, double(reader::kMaxHierWeight));
    p.weights[e] = uint32_t(m);
    p.steps[e] = std::min(unit * m, 1.0);
  }
}

// Codes from the raw table with the current steps, and their errors against it.
void make_codes(HierarchicalParallax& p, const ParallaxCodes& raw,
                const std::vector<double>& per_depth, const std::vector<uint8_t>& keep) {
  const std::size_t texels = std::size_t(raw.resolution) * raw.resolution;
  const std::size_t d = p.steps.size();
  p.codes.assign(d * texels, 0);
  std::vector<double> sum2(d, 0.0), max_offset(d, 0.0), max_depth(d, 0.0);
  std::vector<uint64_t> above(d, 0);
  std::vector<uint32_t> top(d, 0);
  tbb::parallel_for(std::size_t(0), d, [&](std::size_t e) {
    if (!keep.empty() && keep[e] == 0) return;  // not stored: no codes, no error
    const uint16_t* src = raw.codes + e * texels;
    uint16_t* dst = p.codes.data() + e * texels;
    const double step = p.steps[e];
    for (std::size_t t = 0; t < texels; ++t) {
      const double depth = double(src[t]) * raw.depth_scale;
      const double q = step > 0.0 ? std::min(65535.0, std::nearbyint(depth / step)) : 0.0;
      dst[t] = uint16_t(q);
      top[e] = std::max(top[e], uint32_t(q));
      const double depth_error = std::fabs(q * step - depth);
      const double offset_error = depth_error * per_depth[e];
      sum2[e] += offset_error * offset_error;
      max_depth[e] = std::max(max_depth[e], depth_error);
      max_offset[e] = std::max(max_offset[e], offset_error);
      above[e] += offset_error > 0.25;
    }
  });
  double total = 0.0;
  uint64_t count_above = 0;
  p.max_offset_error = p.max_depth_error = 0.0;
  p.max_code = 0;
  for (std::size_t e = 0; e < d; ++e) {  // in order: deterministic
    total += sum2[e];
    count_above += above[e];
    p.max_offset_error = std::max(p.max_offset_error, max_offset[e]);
    p.max_depth_error = std::max(p.max_depth_error, max_depth[e]);
    p.max_code = std::max(p.max_code, top[e]);
  }
  const double stored = keep.empty() ? double(d) : double(kept_direction_count(keep));
  const double entries = double(texels) * std::max(stored, 1.0);
  p.rms_offset_error = std::sqrt(total / entries);
  p.share_above_quarter = double(count_above) / entries;
}

// The difference plane of block d (D = code - ref), the per-texel spread buckets, and the symbols
// with their contexts for shift (sx, sy), in decoding order.
struct BlockSymbols {
  std::vector<uint8_t> ctx, sym;
};

struct Difference {
  std::vector<int32_t> diff;
  std::vector<uint8_t> spread;
};

Difference difference_plane(const HierarchicalParallax& p, uint32_t d) {
  const uint32_t n = uint32_t(p.resolution), dirs = uint32_t(p.dirs);
  const uint64_t texels = uint64_t(n) * n;
  const reader::ParallaxReferences refs = reader::parallax_references(d % dirs, d / dirs, dirs);
  const uint16_t* own = p.codes.data() + d * texels;
  const uint16_t* ref_planes[4];
  uint32_t ref_m[4];
  for (int e = 0; e < refs.count; ++e) {
    ref_planes[e] = p.codes.data() + uint64_t(refs.bin[e]) * texels;
    ref_m[e] = p.weights[refs.bin[e]];
  }
  Difference out;
  out.diff.resize(texels);
  out.spread.resize(texels);
  uint32_t c[4];
  for (uint64_t t = 0; t < texels; ++t) {
    for (int e = 0; e < refs.count; ++e)
      c[e] = ref_planes[e][t];
    const reader::ReferencePrediction r =
        reader::reference_prediction(c, ref_m, refs.count, p.weights[d]);
    out.diff[t] = int32_t(own[t]) - int32_t(r.ref);
    out.spread[t] = uint8_t(r.spread);
  }
  return out;
}

// Calls emit(context, symbol) for every coded symbol of the block with shift (sx, sy), in decoding
// order (the file comment of formats/reader/parallax_hierarchy.hpp: one symbol, or an escape and
// the residual's two bytes).
template <class Emit>
void for_each_symbol(const Difference& plane, uint32_t n, uint32_t sx, uint32_t sy, Emit&& emit) {
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      const uint64_t t = uint64_t(y) * n + x;
      const reader::EntropyPrediction pr =
          reader::predict_parallax_difference(plane.diff.data(), n, x, y, sx, sy, plane.spread[t]);
      // R modulo 65536 into [-32768, 32767].
      const int32_t residual = int32_t(int16_t(uint16_t(uint32_t(plane.diff[t] - pr.value))));
      if (residual >= -reader::kHierDirectMax && residual <= reader::kHierDirectMax) {
        emit(pr.context, residual + reader::kHierDirectMax);
      } else {
        const uint16_t r16 = uint16_t(residual);
        emit(pr.context, reader::kHierEscape);
        emit(reader::kHierEscapeHighContext, r16 >> 8);
        emit(reader::kHierEscapeLowContext, r16 & 0xFF);
      }
    }
}

BlockSymbols block_symbols(const Difference& plane, uint32_t n, uint32_t sx, uint32_t sy) {
  BlockSymbols out;
  const uint64_t texels = uint64_t(n) * n;
  out.ctx.reserve(texels + texels / 16);
  out.sym.reserve(texels + texels / 16);
  for_each_symbol(plane, n, sx, sy, [&](int context, int symbol) {
    out.ctx.push_back(uint8_t(context));
    out.sym.push_back(uint8_t(symbol));
  });
  return out;
}

std::vector<uint64_t> symbol_counts(const Difference& plane, uint32_t n, uint32_t sx, uint32_t sy) {
  std::vector<uint64_t> counts(std::size_t(kHierContexts) * 256, 0);
  for_each_symbol(plane, n, sx, sy,
                  [&](int context, int symbol) { ++counts[std::size_t(context) * 256 + symbol]; });
  return counts;
}

}  // namespace

uint32_t hierarchical_group(uint32_t i, uint32_t j, uint32_t n) {
  const int level = reader::parallax_references(i, j, n).level;
  // Ring: the Chebyshev distance of the bin centre from the grid centre, in quarters of n / 2.
  const int64_t di = std::llabs(2 * int64_t(i) + 1 - int64_t(n));
  const int64_t dj = std::llabs(2 * int64_t(j) + 1 - int64_t(n));
  const int64_t ring = std::min<int64_t>(3, std::max(di, dj) * 4 / (int64_t(n) + 1));
  return uint32_t(4 * level + ring);
}

std::vector<uint8_t> encode_hierarchical_block(const HierarchicalParallax& p, uint32_t d,
                                               uint32_t sx, uint32_t sy, uint32_t group,
                                               const uint16_t* freq) {
  const BlockSymbols s = block_symbols(difference_plane(p, d), uint32_t(p.resolution), sx, sy);
  std::vector<uint8_t> out;
  rans_encode_block(sx, sy, group, s.ctx.data(), s.sym.data(), s.ctx.size(), freq, out);
  return out;
}

HierarchicalParallax hierarchical_parallax(const ParallaxCodes& raw, double max_error,
                                           const std::vector<uint8_t>& keep) {
  const auto start = std::chrono::steady_clock::now();
  check_parallax_compression_input(raw, max_error);
  const uint32_t n = uint32_t(raw.resolution), dirs = uint32_t(raw.dirs);
  const std::size_t d_count = std::size_t(dirs) * dirs;
  const uint64_t texels = uint64_t(n) * n;
  if (!keep.empty()) {
    if (keep.size() != d_count || kept_direction_count(keep) == 0)
      throw_internal_error("hierarchical_parallax: keep needs one entry per direction, one kept");
    std::vector<uint8_t> closed = keep;
    reader::close_under_parallax_references(closed.data(), dirs);
    for (std::size_t d = 0; d < d_count; ++d)
      if ((closed[d] != 0) != (keep[d] != 0))
        throw_internal_error(
            "hierarchical_parallax: the kept directions must include every "
            "direction they reference");
  }
  auto stored = [&](std::size_t d) { return keep.empty() || keep[d] != 0; };
  HierarchicalParallax p;
  p.planned = !keep.empty();
  p.resolution = raw.resolution;
  p.dirs = raw.dirs;
  p.min_cos = raw.min_cos;
  p.reference_height = raw.reference_height;
  p.max_offset = raw.max_offset;

  // Quantisation: steps from the target, shrunk while the measured error is above it.
  const std::vector<double> per_depth =
      parallax_offset_per_depth(raw.resolution, raw.dirs, raw.min_cos);
  std::vector<double> per_depth_eff(d_count);
  for (uint32_t j = 0; j < dirs; ++j)
    for (uint32_t i = 0; i < dirs; ++i) {
      const double own = per_depth[std::size_t(j) * dirs + i];
      double t = own;
      if (i > 0) t = std::max(t, per_depth[std::size_t(j) * dirs + i - 1]);
      if (i + 1 < dirs) t = std::max(t, per_depth[std::size_t(j) * dirs + i + 1]);
      if (j > 0) t = std::max(t, per_depth[std::size_t(j - 1) * dirs + i]);
      if (j + 1 < dirs) t = std::max(t, per_depth[std::size_t(j + 1) * dirs + i]);
      // Near the pole T grows threefold from one ring to the next: half the neighbours' largest
      // T keeps the innermost bins' steps within reach of the next ring's (and changes no other).
      per_depth_eff[std::size_t(j) * dirs + i] = std::max(own, 0.5 * t);
    }
  // The steps depend on the grid, the relief's range (the raw table's scale) and the target only,
  // not on the rays: a scene-planned bake that casts some directions gets the same codes for them
  // as the full bake. 2 % below the target leaves room for the measured error (within it on every
  // example fabric, 0.047-0.049 texel); only if it is still above are the steps shrunk.
  const double range = raw.depth_scale * 65535.0;
  double scale = kStepMargin * max_error;
  for (int round = 1; round <= kMaxQuantisationRounds; ++round) {
    make_steps(p, per_depth_eff, range, scale);
    make_codes(p, raw, per_depth, keep);
    p.quantisation_rounds = round;
    if (p.rms_offset_error <= max_error) break;  // (the finest steps may still miss a tiny target:
    scale *= 0.98 * max_error / p.rms_offset_error;  // the caller warns)
  }
  p.seconds_quantise = seconds_since(start);

  // Coding.
  const auto coding = std::chrono::steady_clock::now();
  {
    // The tile's repeats, from the direction with the finest codes (the largest code: near the
    // pole the steps are coarse and a plane may be almost constant, which repeats everywhere).
    std::size_t mid = 0;
    uint16_t finest = 0;
    for (std::size_t d = 0; d < d_count; ++d) {
      if (!stored(d)) continue;
      const uint16_t* plane = p.codes.data() + d * texels;
      const uint16_t top = *std::max_element(plane, plane + texels);
      if (top > finest || (finest == 0 && !stored(mid))) finest = top, mid = d;
    }
    std::vector<uint8_t> low(texels);  // its codes' low bytes (a fingerprint)
    for (uint64_t t = 0; t < texels; ++t)
      low[t] = uint8_t(p.codes[mid * texels + t]);
    // Shifts shorter than a sixteenth of the tile (at least 4 texels) only repeat what the
    // median predictor already sees; the tile's real repeats are longer.
    p.candidates = parallax_shift_candidates(low.data(), n, 3, std::max<uint32_t>(4, n / 16));
  }
  std::vector<ShiftChoice> choice(d_count);
  tbb::parallel_for(std::size_t(0), d_count, [&](std::size_t d) {
    if (!stored(d)) {  // an empty block: no counts
      choice[d].counts.assign(std::size_t(kHierContexts) * 256, 0);
      return;
    }
    const Difference plane = difference_plane(p, uint32_t(d));
    choice[d] = choose_shift(
        p.candidates, [&](uint32_t sx, uint32_t sy) { return symbol_counts(plane, n, sx, sy); });
  });
  // Frequency tables: one set per group of blocks. More groups fit the blocks better but cost
  // kHierContexts * 512 bytes each; of the partitions {all}, {level}, {level x ring} the bake
  // keeps the one with the smallest estimated total (coded bits under each group's quantised
  // frequencies, plus the tables).
  const std::size_t table_size = std::size_t(kHierContexts) * 256;
  struct Partition {
    uint32_t groups;
    std::vector<uint32_t> group_of;
    std::vector<uint16_t> tables;
    double bytes;
  };
  auto partition = [&](uint32_t groups, auto&& group_of_bin) {
    Partition part{groups, std::vector<uint32_t>(d_count), {}, 0.0};
    part.tables.assign(groups * table_size, 0);
    for (std::size_t d = 0; d < d_count; ++d)
      part.group_of[d] = group_of_bin(uint32_t(d % dirs), uint32_t(d / dirs));
    for (uint32_t g = 0; g < groups; ++g) {
      std::vector<uint64_t> sum(table_size, 0);
      for (std::size_t d = 0; d < d_count; ++d)
        if (part.group_of[d] == g)
          for (std::size_t k = 0; k < table_size; ++k)
            sum[k] += choice[d].counts[k];
      uint16_t* freq = part.tables.data() + g * table_size;
      for (int c = 0; c < kHierContexts; ++c)
        normalise_frequencies(sum.data() + std::size_t(c) * 256, freq + std::size_t(c) * 256);
      double bits = 0.0;
      for (std::size_t k = 0; k < table_size; ++k)
        if (sum[k] > 0) bits -= double(sum[k]) * std::log2(double(freq[k]) / reader::kRansScale);
      part.bytes += bits / 8.0 + double(table_size) * 2.0;
    }
    return part;
  };
  Partition best = partition(1, [](uint32_t, uint32_t) { return 0u; });
  for (Partition candidate :
       {partition(3,
                  [&](uint32_t i, uint32_t j) {
                    return uint32_t(reader::parallax_references(i, j, dirs).level);
                  }),
        partition(12, [&](uint32_t i, uint32_t j) { return hierarchical_group(i, j, dirs); })})
    if (candidate.bytes < best.bytes) best = std::move(candidate);
  p.groups = best.groups;
  p.tables = std::move(best.tables);
  const std::vector<uint32_t>& group_of = best.group_of;
  std::vector<std::vector<uint8_t>> blocks(d_count);
  tbb::parallel_for(std::size_t(0), d_count, [&](std::size_t d) {
    if (!stored(d)) return;  // an empty block
    blocks[d] = encode_hierarchical_block(p, uint32_t(d), choice[d].sx, choice[d].sy, group_of[d],
                                          p.tables.data() + group_of[d] * table_size);
  });
  p.offsets.assign(d_count + 1, 0);
  for (std::size_t d = 0; d < d_count; ++d) {
    p.offsets[d + 1] = p.offsets[d] + blocks[d].size();
    p.shifted_blocks += stored(d) && (choice[d].sx | choice[d].sy) != 0;
  }
  p.stream.reserve(p.offsets.back());
  for (auto& b : blocks)
    p.stream.insert(p.stream.end(), b.begin(), b.end());
  p.seconds_code = seconds_since(coding);
  return p;
}

std::size_t kept_direction_count(const std::vector<uint8_t>& keep) {
  return std::size_t(std::count_if(keep.begin(), keep.end(), [](uint8_t k) { return k != 0; }));
}

namespace {
// The info record of the table: its shape and measured errors, bits 16, with `flags`.
reader::CompressedParallaxInfoRecord info_record(const HierarchicalParallax& p, uint32_t flags) {
  reader::CompressedParallaxInfoRecord info{};
  info.resolution = uint32_t(p.resolution);
  info.dirs = uint32_t(p.dirs);
  info.bits = 16;
  info.flags = flags;
  info.min_cos = p.min_cos;
  info.reference_height = p.reference_height;
  info.max_offset = p.max_offset;
  info.rms_offset_error = p.rms_offset_error;
  info.max_offset_error = p.max_offset_error;
  info.max_depth_error = p.max_depth_error;
  return info;
}
}  // namespace

std::vector<formats::Section> hierarchical_parallax_sections(const HierarchicalParallax& p) {
  using reader::SectionType;
  const uint32_t d = uint32_t(p.dirs * p.dirs);
  const uint16_t v = reader::kHierParallaxVersion;
  const reader::CompressedParallaxInfoRecord info =
      info_record(p, p.planned ? reader::kEntropyPlannedFlag : 0u);
  if (p.stream.size() > 0xFFFFFFFFull)
    throw_input_error("parallax: the entropy-coded table exceeds 4 GiB");
  std::vector<formats::Section> out;
  out.push_back(formats::make_record_section(
      SectionType::ParallaxEntropy, reader::kEntropyParallaxInfoInstance,
      std::span<const reader::CompressedParallaxInfoRecord>(&info, 1), v));
  out.push_back(formats::make_array_section<double>(
      SectionType::ParallaxEntropy, reader::kEntropyParallaxStepsInstance, p.steps, {d}, v));
  out.push_back(formats::make_array_section<uint64_t>(SectionType::ParallaxEntropy,
                                                      reader::kEntropyParallaxOffsetsInstance,
                                                      p.offsets, {d + 1}, v));
  out.push_back(formats::make_array_section<uint8_t>(SectionType::ParallaxEntropy,
                                                     reader::kEntropyParallaxStreamInstance,
                                                     p.stream, {uint32_t(p.stream.size())}, v));
  out.push_back(formats::make_array_section<uint16_t>(
      SectionType::ParallaxEntropy, reader::kEntropyParallaxTablesInstance, p.tables,
      {p.groups, uint32_t(kHierContexts), 256u}, v));
  out.push_back(formats::make_array_section<uint32_t>(
      SectionType::ParallaxEntropy, reader::kHierParallaxWeightsInstance, p.weights, {d}, v));
  return out;
}

}  // namespace clothbake::compress

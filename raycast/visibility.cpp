#include "raycast/visibility.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "model/directions.hpp"
#include "model/splitmix64.hpp"
#include "raycast/asg_fit.hpp"
#include "raycast/height_range.hpp"
#include "raycast/heightfield_scene.hpp"
#include "raycast/texel_blocks.hpp"

namespace clothbake::raycast {

double VisibilitySamples::visible_fraction(std::size_t texel) const {
  const int count = dirs * dirs;
  if (count == 0) return 0.0;
  std::size_t seen = 0;
  for (int w = 0; w < words_per_texel; ++w)
    seen += std::size_t(std::popcount(bits[texel * std::size_t(words_per_texel) + w]));
  return double(seen) / double(count);
}

void validate_visibility_settings(const VisibilitySettings& settings) {
  if (settings.dirs < 1 || settings.dirs > 256)
    throw_input_error("bake.visibility_dirs = " + std::to_string(settings.dirs) +
                      " is out of range: expected 1 to 256 (directions per side of the grid)");
  if (!(settings.normal_offset_texels > 0.0 && settings.normal_offset_texels <= 1.0))
    throw_input_error(
        "visibility normal offset = " + std::to_string(settings.normal_offset_texels) +
        " texels is out of range: expected 0 < offset <= 1");
  if (settings.rings < -1 || settings.rings > 64)
    throw_input_error("visibility rings = " + std::to_string(settings.rings) +
                      " is out of range: expected -1 (automatic) or 0 to 64");
  if (!(settings.fit_warn_rms > 0.0))
    throw_input_error("visibility fit warning threshold must be > 0");
  if (!(settings.max_sideways_tiles > 0.0))
    throw_input_error("visibility sideways budget must be > 0 tile widths");
}

VisibilitySamples sample_visibility(const FabricMaps& maps, const VisibilitySettings& settings,
                                    const std::function<void(double)>& progress) {
  validate_visibility_settings(settings);
  const int n = maps.resolution;
  if (n < 1 || maps.height.size() != maps.texel_count())
    throw_input_error("height map: expected " + std::to_string(maps.texel_count()) +
                      " texels for resolution " + std::to_string(n) + ", got " +
                      std::to_string(maps.height.size()));
  const double bytes = double(maps.texel_count()) * settings.dirs * settings.dirs / 8.0;
  if (bytes > kMaxVisibilitySampleBytes)
    throw_input_error("bake.resolution = " + std::to_string(n) +
                      " with bake.visibility_dirs = " + std::to_string(settings.dirs) + " needs " +
                      std::to_string(int64_t(bytes / (1 << 20))) +
                      " MiB of visibility samples, above the limit of " +
                      std::to_string(int64_t(kMaxVisibilitySampleBytes / (1 << 20))) +
                      " MiB: lower the resolution or the directions");
  // Plain variables, not a structured binding: clang before 16 cannot capture bindings in the
  // lambdas below (the sanitizer build uses clang).
  const HeightRange heights = height_range(maps);
  const double z_min = heights.min, z_max = heights.max;

  VisibilitySamples samples;
  samples.resolution = n;
  samples.dirs = settings.dirs;
  const int dir_count = settings.dirs * settings.dirs;
  samples.words_per_texel = (dir_count + 63) / 64;
  const std::size_t texels = maps.texel_count();
  samples.bits.assign(texels * std::size_t(samples.words_per_texel), 0);
  auto set_all_visible = [&](std::size_t texel) {
    for (int dir = 0; dir < dir_count; ++dir)
      samples.bits[texel * samples.words_per_texel + dir / 64] |= uint64_t(1) << (dir % 64);
  };
  const double range = z_max - z_min;
  if (!(range > 0.0)) {
    for (std::size_t t = 0; t < texels; ++t)
      set_all_visible(t);
    return samples;
  }

  model::DirectionGrid<double> grid{settings.dirs, 0.0};
  std::vector<model::Vec3d> light(static_cast<std::size_t>(dir_count));
  for (int j = 0; j < settings.dirs; ++j)
    for (int i = 0; i < settings.dirs; ++i) {
      light[std::size_t(grid.bin_index(i, j))] = grid.bin_center(i, j);
    }
  const int rings = settings.rings >= 0 ? settings.rings : automatic_rings(range);
  PeriodicHeightField field(maps.height, n, rings, settings.max_sideways_tiles);
  samples.rings = rings;

  // Ray origins: texel-centre vertex + offset along the central-difference normal.
  const double offset = settings.normal_offset_texels / double(n);
  std::vector<model::Vec3d> origin(texels);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      origin[maps.index(x, y)] = field.lifted_surface_point(x, y, offset);

  RayCounters counters;
  const TexelBlocks blocks(n);
  std::atomic<int> tiles_done{0};
  const int words = samples.words_per_texel;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, blocks.tile_count()), [&](const tbb::blocked_range<int>& r) {
        RayPacket packet;
        std::array<bool, RayPacket::kWidth> hit;
        std::array<int, RayPacket::kWidth> lane_texel;
        RayCounters local;  // added once per task (shared counters per packet ping-pong)
        for (int tile = r.begin(); tile != r.end(); ++tile) {
          for (int dir = 0; dir < dir_count; ++dir) {
            const model::Vec3d w = light[std::size_t(dir)];
            for (int p = 0; p < blocks.packets_per_tile(); ++p) {
              packet.count = blocks.packet_texels(tile, p, lane_texel);
              if (packet.count == 0) continue;
              for (int l = 0; l < packet.count; ++l) {
                const model::Vec3d& o = origin[std::size_t(lane_texel[l])];
                packet.ox[l] = o.x;
                packet.oy[l] = o.y;
                packet.oz[l] = o.z;
                packet.dx[l] = w.x;
                packet.dy[l] = w.y;
                packet.dz[l] = w.z;
                // Above z_max nothing can be hit: the ray ends there (a lane with t_max <= 0, from
                // a point above every height, is not cast and counts as visible).
                packet.t_max[l] = (z_max - o.z) / w.z + 1e-6;
              }
              field.occluded(packet, hit, &local);
              for (int l = 0; l < packet.count; ++l)
                if (!hit[l])
                  samples.bits[std::size_t(lane_texel[l]) * words + dir / 64] |= uint64_t(1)
                                                                                 << (dir % 64);
            }
          }
          const int done = tiles_done.fetch_add(1, std::memory_order_relaxed) + 1;
          if (progress) progress(double(done) / double(blocks.tile_count()));
        }
        counters.add(local);
      });
  samples.rays = counters.rays.load();
  samples.segments = counters.segments.load();
  samples.unresolved_rays = counters.unresolved.load();
  samples.max_sideways_tiles = field.max_sideways_tiles();
  if (samples.unresolved_rays > 0) {
    char budget[32], range[32];
    std::snprintf(budget, sizeof budget, "%g", field.max_sideways_tiles());
    std::snprintf(range, sizeof range, "%g", z_max - z_min);
    warn("visibility: " + std::to_string(samples.unresolved_rays) + " of " +
         std::to_string(samples.rays) + " rays skimmed the relief for " + budget +
         " tile widths sideways without being blocked and were counted as visible (the sideways "
         "budget, docs/raycast.md): the relief is very tall for its tile (height range " +
         range + " tiles)");
  }
  return samples;
}

FitDirections visibility_fit_directions(int dirs) {
  const model::DirectionGrid<double> grid{dirs, 0.0};
  FitDirections directions;
  for (int j = 0; j < dirs; ++j)
    for (int i = 0; i < dirs; ++i) {
      const model::Vec3d d = grid.bin_center(i, j);
      directions.push_back(d.x, d.y, d.z);
    }
  return directions;
}

VisibilityAsgs fit_visibility(const VisibilitySamples& samples, const VisibilitySettings& settings,
                              const std::function<void(double)>& progress) {
  validate_visibility_settings(settings);
  VisibilityAsgs out;
  out.resolution = samples.resolution;
  const std::size_t texels = std::size_t(samples.resolution) * std::size_t(samples.resolution);
  out.records.resize(texels);
  out.fit_error.resize(texels);
  const int dir_count = samples.dirs * samples.dirs;
  const FitDirections directions = visibility_fit_directions(samples.dirs);

  // Texels with the same visibility samples get the same fit (fit_asg and the packing depend on
  // nothing else), and a woven tile repeats its relief: the 256^2 example weaves have 4 % (satin)
  // to 37 % (plain) distinct patterns. So each distinct pattern is fitted once, the first texel
  // that has it in texel order standing for it; the records are bit for bit those of fitting every
  // texel, for any thread count.
  const std::size_t words = std::size_t(samples.words_per_texel);
  auto pattern = [&](std::size_t t) { return samples.bits.data() + t * words; };
  std::vector<uint32_t> pattern_of(texels);  // index into `firsts`
  std::vector<uint32_t> firsts;              // the first texel of each distinct pattern
  {
    // Open addressing with linear probing over a power-of-two table at most half full: 4 bytes
    // per slot, 8 to 16 bytes per texel (docs/raycast.md; the memory estimate counts them, and
    // `firsts` at up to 8 bytes a texel while its vector grows).
    constexpr uint32_t kEmpty = ~uint32_t(0);
    const std::size_t capacity = std::bit_ceil(std::max<std::size_t>(2 * texels, 2));
    std::vector<uint32_t> table(capacity, kEmpty);
    for (std::size_t t = 0; t < texels; ++t) {
      uint64_t h = 0x243f6a8885a308d3ull;
      for (std::size_t w = 0; w < words; ++w) {
        h ^= pattern(t)[w];
        h = model::splitmix64_next(h);
      }
      std::size_t slot = std::size_t(h) & (capacity - 1);
      while (table[slot] != kEmpty &&
             !std::equal(pattern(t), pattern(t) + words, pattern(firsts[table[slot]])))
        slot = (slot + 1) & (capacity - 1);
      if (table[slot] == kEmpty) {
        table[slot] = uint32_t(firsts.size());
        firsts.push_back(uint32_t(t));
      }
      pattern_of[t] = table[slot];
    }
  }
  out.distinct_patterns = firsts.size();

  std::vector<model::AsgRecord> fitted_records(firsts.size());
  std::vector<float> fitted_errors(firsts.size());
  std::atomic<std::size_t> fitted{0};
  out.fit_evaluations = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, firsts.size(), 16), uint64_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, uint64_t evaluations) {
        std::vector<uint8_t> visible(static_cast<std::size_t>(dir_count));
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
          const std::size_t t = firsts[k];
          for (int dir = 0; dir < dir_count; ++dir)
            visible[dir] = samples.visible(t, dir) ? 1 : 0;
          AsgFitResult fit = fit_asg(directions, visible.data());
          model::AsgRecord record = model::pack_asg(fit.params);
          // The error of what is stored (the packed lobe), rounded to the stored float.
          fitted_records[k] = record;
          fitted_errors[k] =
              float(asg_rms_error(directions, visible.data(), model::unpack_asg<double>(record)));
          evaluations += uint64_t(fit.evaluations);
        }
        const std::size_t done = fitted.fetch_add(r.size(), std::memory_order_relaxed) + r.size();
        if (progress) progress(double(done) / double(firsts.size()));
        return evaluations;
      },
      std::plus<uint64_t>());
  // Statistics in texel order (independent of how TBB split the fits): the first texel of the
  // largest error (a NaN error is never it), the count above the warning, the mean.
  double largest = -1, sum = 0;
  for (std::size_t t = 0; t < texels; ++t) {
    out.records[t] = fitted_records[pattern_of[t]];
    const float err = fitted_errors[pattern_of[t]];
    out.fit_error[t] = err;
    if (double(err) > largest) {
      largest = double(err);
      out.worst_texel = t;
    }
    out.texels_above_warning += double(err) > settings.fit_warn_rms ? 1 : 0;
    sum += double(err);
  }
  out.max_fit_error = std::max(largest, 0.0);
  out.mean_fit_error = texels ? sum / double(texels) : 0.0;
  // No warning: a large fit error is the model's (one smooth lobe against a binary horizon), not
  // something a setting fixes; the counts go to the asset's metadata (docs/raycast.md).
  return out;
}

}  // namespace clothbake::raycast

#include "raycast/parallax.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>

#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "model/directions.hpp"
#include "raycast/height_range.hpp"
#include "raycast/heightfield_scene.hpp"
#include "raycast/texel_blocks.hpp"

namespace clothbake::raycast {
namespace {

constexpr double kCodeMax = 65535.0;

// std::round for 0 <= v < 2^52 without a libm call (the build targets baseline x86-64, which has
// no rounding instruction): v - trunc(v) is exact there, and halves go up as std::round's do.
// Branch-free on purpose: the fraction is random, so a branch would be mispredicted half the
// time (measured: slower than the libm call).
double round_nonnegative(double v) {
  const double whole = double(int64_t(v));
  return whole + double(int(v - whole >= 0.5));
}

void atomic_max(std::atomic<double>& target, double value) {
  double current = target.load(std::memory_order_relaxed);
  while (value > current &&
         !target.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
  }
}

}  // namespace

void validate_parallax_settings(const ParallaxSettings& settings) {
  if (settings.dirs < 1 || settings.dirs > 256)
    throw_input_error("bake.parallax_dirs = " + std::to_string(settings.dirs) +
                      " is out of range: expected 1 to 256 (directions per side of the grid)");
  if (!(settings.min_cos >= 0.0 && settings.min_cos < 1.0))
    throw_input_error("bake.parallax_min_cos = " + std::to_string(settings.min_cos) +
                      " is out of range: expected 0 <= min_cos < 1 (the paper uses 0.6)");
  if (settings.rings < -1 || settings.rings > 64)
    throw_input_error("parallax rings = " + std::to_string(settings.rings) +
                      " is out of range: expected -1 (automatic) or 0 to 64");
}

ParallaxTable bake_parallax(const FabricMaps& maps, const ParallaxSettings& settings,
                            const ProgressCallback& progress) {
  validate_parallax_settings(settings);
  const int n = maps.resolution;
  if (n < 1 || maps.height.size() != maps.texel_count())
    throw_input_error("height map: expected " + std::to_string(maps.texel_count()) +
                      " texels for resolution " + std::to_string(n) + ", got " +
                      std::to_string(maps.height.size()));
  const double bytes = double(maps.texel_count()) * settings.dirs * settings.dirs * 6.0;
  if (bytes > kMaxParallaxBytes)
    throw_input_error("bake.resolution = " + std::to_string(n) + " with bake.parallax_dirs = " +
                      std::to_string(settings.dirs) + " needs a parallax table and SAT of " +
                      std::to_string(int64_t(bytes / (1 << 20))) + " MiB, above the limit of " +
                      std::to_string(int64_t(kMaxParallaxBytes / (1 << 20))) +
                      " MiB: lower the resolution or the directions");
  // Plain variables, not a structured binding: clang before 16 cannot capture bindings in the
  // lambdas below (the sanitizer build uses clang).
  const HeightRange heights = height_range(maps);
  const double z_min = heights.min, z_max = heights.max;

  ParallaxTable table;
  table.resolution = n;
  table.dirs = settings.dirs;
  table.min_cos = settings.min_cos;
  table.reference_height = z_max;
  const std::size_t texels = table.texel_count();
  const int dir_count = settings.dirs * settings.dirs;
  if (!settings.keep.empty() && settings.keep.size() != std::size_t(dir_count))
    throw_internal_error("bake_parallax: keep has " + std::to_string(settings.keep.size()) +
                         " entries for " + std::to_string(dir_count) + " directions");
  table.depth.assign(std::size_t(dir_count) * texels, 0);
  const double range = z_max - z_min;
  if (!(range > 0.0)) return table;  // flat: every ray hits the reference plane, r = 0
  table.depth_scale = range / kCodeMax;

  model::DirectionGrid<double> grid{settings.dirs, settings.min_cos};
  std::vector<model::Vec3d> view(static_cast<std::size_t>(dir_count));
  for (int j = 0; j < settings.dirs; ++j)
    for (int i = 0; i < settings.dirs; ++i) {
      view[std::size_t(grid.bin_index(i, j))] = grid.bin_center(i, j);
    }
  const int rings = settings.rings >= 0 ? settings.rings : automatic_rings(range);
  PeriodicHeightField field(maps.height, n, rings);
  table.stats.rings = rings;

  // Rays start slightly above the reference plane (so that a texel at z_ref is hit at t > 0) and
  // end slightly below the lowest height (every ray must hit before; see unresolved below).
  const double lift = std::max(1e-3 * range, 1e-6);
  const double z_origin = z_max + lift;
  RayCounters counters;
  std::atomic<uint64_t> recast{0}, unresolved{0};
  std::atomic<double> max_error{0.0};
  std::vector<std::atomic<uint16_t>> max_code(static_cast<std::size_t>(dir_count));
  for (auto& m : max_code)
    m.store(0);

  // Texel-centre coordinates, computed once (the same values as (x + 0.5) / n per ray).
  std::vector<double> centre(static_cast<std::size_t>(n));
  for (int x = 0; x < n; ++x)
    centre[std::size_t(x)] = (x + 0.5) / n;

  const TexelBlocks blocks(n);
  std::atomic<int> tiles_done{0};
  tbb::parallel_for(
      tbb::blocked_range<int>(0, blocks.tile_count()), [&](const tbb::blocked_range<int>& r) {
        RayPacket packet;
        std::array<double, RayPacket::kWidth> t_hit;
        std::array<int, RayPacket::kWidth> lane_texel, lane_x, lane_y;
        double local_max_error = 0.0;
        // Counted per task and added once: shared counters bumped per packet by both threads
        // ping-pong their cache line.
        RayCounters local;
        for (int tile = r.begin(); tile != r.end(); ++tile) {
          for (int dir = 0; dir < dir_count; ++dir) {
            if (!settings.keep.empty() && settings.keep[std::size_t(dir)] == 0) continue;
            const model::Vec3d o = view[std::size_t(dir)];
            const double t_max = (lift + range + lift) / o.z;
            for (int l = 0; l < RayPacket::kWidth; ++l) {
              packet.oz[l] = z_origin;
              packet.dx[l] = -o.x;
              packet.dy[l] = -o.y;
              packet.dz[l] = -o.z;
              packet.t_max[l] = t_max;
            }
            uint16_t* codes = table.depth.data() + std::size_t(dir) * texels;
            uint16_t tile_max_code = 0;
            for (int p = 0; p < blocks.packets_per_tile(); ++p) {
              packet.count = blocks.packet_texels(tile, p, lane_texel, lane_x, lane_y);
              if (packet.count == 0) continue;
              for (int l = 0; l < packet.count; ++l) {
                packet.ox[l] = centre[std::size_t(lane_x[l])];
                packet.oy[l] = centre[std::size_t(lane_y[l])];
              }
              field.first_hits(packet, t_hit, &local);
              for (int l = 0; l < packet.count; ++l) {
                double t = t_hit[l];
                if (!(t < std::numeric_limits<double>::infinity())) {
                  // An Embree edge leak (its triangle test is not watertight): cast again from
                  // origins moved by a fraction of a float ulp-scale step, deterministically.
                  for (int attempt = 1; attempt <= 2 && !(t < t_max * 2); ++attempt) {
                    model::Vec3d origin{packet.ox[l] + attempt * 3.1e-7,
                                        packet.oy[l] + attempt * 1.7e-7, z_origin};
                    SurfaceHit h = field.first_hit(origin, -o, t_max);
                    if (h.hit) t = h.t;
                  }
                  recast.fetch_add(1, std::memory_order_relaxed);
                  if (!(t < t_max * 2)) {
                    unresolved.fetch_add(1, std::memory_order_relaxed);
                    t = t_max;
                  }
                }
                double depth = std::clamp(t * o.z - lift, 0.0, range);
                double code = round_nonnegative(depth / table.depth_scale);
                code = std::clamp(code, 0.0, kCodeMax);
                local_max_error =
                    std::max(local_max_error, std::abs(depth - code * table.depth_scale));
                uint16_t c16 = uint16_t(code);
                tile_max_code = std::max(tile_max_code, c16);
                codes[lane_texel[l]] = c16;
              }
            }
            auto& m = max_code[std::size_t(dir)];
            uint16_t cur = m.load(std::memory_order_relaxed);
            while (tile_max_code > cur &&
                   !m.compare_exchange_weak(cur, tile_max_code, std::memory_order_relaxed)) {
            }
          }
          const int done = tiles_done.fetch_add(1, std::memory_order_relaxed) + 1;
          if (progress) progress(double(done) / double(blocks.tile_count()));
        }
        atomic_max(max_error, local_max_error);
        counters.rays.fetch_add(local.rays.load(), std::memory_order_relaxed);
        counters.segments.fetch_add(local.segments.load(), std::memory_order_relaxed);
      });

  table.stats.rays = counters.rays.load();
  table.stats.segments = counters.segments.load();
  table.stats.recast_rays = recast.load();
  table.stats.unresolved_rays = unresolved.load();
  table.stats.max_quantization_error = max_error.load();
  for (int dir = 0; dir < dir_count; ++dir) {
    const model::Vec3d o = view[std::size_t(dir)];
    double tan_theta = std::sqrt(o.x * o.x + o.y * o.y) / o.z;
    table.stats.max_sideways =
        std::max(table.stats.max_sideways,
                 max_code[std::size_t(dir)].load() * table.depth_scale * tan_theta);
  }

  if (table.stats.unresolved_rays > 0)
    warn("parallax: " + std::to_string(table.stats.unresolved_rays) + " of " +
         std::to_string(table.stats.rays) +
         " rays never hit the height field (numerical leaks through triangle edges); their depth "
         "was set to the bottom of the height range, so those table entries cannot be trusted");
  if (table.stats.max_sideways > 1.0)
    warn("parallax: the height range " + std::to_string(range) +
         " (tile-side units) makes parallax offsets reach " +
         std::to_string(table.stats.max_sideways) +
         " tiles sideways; the table is exact for this height field, but a fabric this tall "
         "relative to its tile is outside what the surface model is meant for (check the height "
         "units)");
  return table;
}

std::vector<uint32_t> parallax_sat(const ParallaxTable& table) {
  std::vector<uint32_t> sat(table.depth.size());
  parallax_sat(table.depth.data(), table.resolution, table.dirs * table.dirs, sat.data());
  return sat;
}

void parallax_sat(const uint16_t* codes, int resolution, int dir_count, uint32_t* out) {
  const int n = resolution;
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  tbb::parallel_for(0, dir_count, [&](int dir) {
    const uint16_t* src = codes + std::size_t(dir) * texels;
    uint32_t* dst = out + std::size_t(dir) * texels;
    for (int y = 0; y < n; ++y) {
      uint32_t row = 0;  // unsigned arithmetic wraps modulo 2^32 by definition
      for (int x = 0; x < n; ++x) {
        row += src[std::size_t(y) * n + x];
        dst[std::size_t(y) * n + x] = row + (y > 0 ? dst[std::size_t(y - 1) * n + x] : 0u);
      }
    }
  });
}

}  // namespace clothbake::raycast

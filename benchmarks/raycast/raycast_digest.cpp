// Digests of what the ray-casting stages compute, so that a speed change can be shown to leave the
// results bit for bit unchanged (docs/raycast.md, "Performance"): run it before and after and
// compare the lines.
//   build-*/bin/raycast_digest            (plain weave 128^2 and a tall sine field 64^2, 32^2 dirs)
// Prints one line per workload: FNV-1a 64 of the parallax depth codes, of the parallax SAT, of the
// visibility bits, and the recast / unresolved / segment counts; then how much the parallax codes
// of two neighbourhood sizes (rings) differ.
#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "raycast/parallax.hpp"
#include "raycast/visibility.hpp"
#include "tests/raycast/synthetic_fields.hpp"

namespace {

using namespace clothbake;

uint64_t fnv1a(const void* data, std::size_t bytes) {
  uint64_t h = 1469598103934665603ull;
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

// How far the parallax codes of two neighbourhood sizes differ: the rays are the same, but an
// instanced copy transforms them in float, so a hit can move by a float ulp and its code by one.
void compare_rings(const char* name, const FabricMaps& maps, int dirs, int rings_a, int rings_b) {
  raycast::ParallaxSettings ps;
  ps.dirs = dirs;
  ps.rings = rings_a;
  const raycast::ParallaxTable a = raycast::bake_parallax(maps, ps);
  ps.rings = rings_b;
  const raycast::ParallaxTable b = raycast::bake_parallax(maps, ps);
  std::size_t differ = 0;
  int largest = 0;
  for (std::size_t i = 0; i < a.depth.size(); ++i) {
    const int d = std::abs(int(a.depth[i]) - int(b.depth[i]));
    differ += d != 0;
    largest = std::max(largest, d);
  }
  std::printf("%-16s rings %d vs %d: %zu of %zu codes differ, by at most %d (%.3g tile sides)\n",
              name, rings_a, rings_b, differ, a.depth.size(), largest, largest * a.depth_scale);
}

void digest(const char* name, const FabricMaps& maps, int dirs, int rings) {
  raycast::ParallaxSettings ps;
  ps.dirs = dirs;
  ps.rings = rings;
  raycast::ParallaxTable table = raycast::bake_parallax(maps, ps);
  std::vector<uint32_t> sat = raycast::parallax_sat(table);
  raycast::VisibilitySettings vs;
  vs.dirs = dirs;
  vs.rings = rings;
  raycast::VisibilitySamples v = raycast::sample_visibility(maps, vs);
  std::printf("%-16s rings %2d  codes %016" PRIx64 "  sat %016" PRIx64 "  bits %016" PRIx64
              "  recast %" PRIu64 " unresolved %" PRIu64 " segments %" PRIu64 "/%" PRIu64 "\n",
              name, rings, fnv1a(table.depth.data(), table.depth.size() * 2),
              fnv1a(sat.data(), sat.size() * 4), fnv1a(v.bits.data(), v.bits.size() * 8),
              table.stats.recast_rays, table.stats.unresolved_rays, table.stats.segments,
              v.segments);
}

}  // namespace

int main() {
  const FabricMaps weave = raycast::rctest::plain_weave_maps(128);
  digest("weave128", weave, 32, -1);
  digest("weave128", weave, 32, 1);
  // Tall: offsets of several tiles, so rays need many segments.
  const FabricMaps tall = raycast::rctest::maps_from(64, [](double u, double v) {
    return 0.9 * std::sin(6.283185307179586 * u) * std::cos(6.283185307179586 * 2 * v);
  });
  digest("tall64", tall, 32, -1);
  digest("tall64", tall, 32, 0);
  compare_rings("weave128", weave, 32, 0, 1);
  compare_rings("tall64", tall, 32, 0, 2);
  return 0;
}

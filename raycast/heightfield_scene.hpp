// The periodic height field of one fabric tile as an Embree 3 scene, and the ray queries every
// ray-casting stage uses (parallax first hits, visibility occlusion, the CGAL cross-check).
//
// Geometry (docs/raycast.md, "The height-field mesh"): one vertex per texel centre,
// ((x + 0.5) / N, (y + 0.5) / N, height[y * N + x]) in tile-side units; each texel quad between the
// centres (x, y), (x+1, y), (x+1, y+1), (x, y+1) (indices wrapped modulo N) is split along the
// (x, y)-(x+1, y+1) diagonal into two triangles. This piecewise-linear surface is periodic with
// period 1 in x and y. The Embree mesh of one tile holds the quads x, y in [-1, N] (one ring of
// quads more than a period on every side, so that neighbouring copies overlap and no ray can slip
// through a seam between copies), and the scene holds (2 rings + 1)^2 translated instances of it.
//
// Rays longer than the replicated neighbourhood are cut into segments: when a segment leaves the
// neighbourhood the ray's origin is wrapped back into the centre tile (periodicity) and the
// remaining part is cast again, so every ray is exact however far it travels sideways; more rings
// only mean fewer segments.
//
// The sideways budget: a ray is followed at most `max_sideways_tiles` tile widths sideways
// (kMaxSidewaysTiles by default). A ray that would go further is cast only that far; if it hits
// nothing there it answers "no hit" (not occluded) and is counted in RayCounters::unresolved. This
// bounds every query's cost (about budget / (2 rings + 1) Embree casts) whatever the relief and
// direction; docs/raycast.md, "The sideways budget".
#pragma once

#include <embree3/rtcore.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

#include "model/vec.hpp"

namespace clothbake::raycast {

using model::Vec3d;

// Up to 16 rays (one Embree packet). Inactive lanes have active[i] == false.
struct RayPacket {
  static constexpr int kWidth = 16;
  int count = 0;                                // lanes 0 .. count-1 are used
  std::array<double, kWidth> ox{}, oy{}, oz{};  // origin (any x, y: wrapped internally)
  std::array<double, kWidth> dx{}, dy{}, dz{};  // unit direction
  std::array<double, kWidth> t_max{};           // segment end, > 0
};

// Where a first hit landed: the triangle of the infinite periodic surface.
struct SurfaceHit {
  bool hit = false;
  double t = 0.0;      // ray parameter of the hit (tile-side units along a unit direction)
  long quad_x = 0;     // quad (x, y) of the infinite grid: texel-centre cell [x, x+1] x [y, y+1]
  long quad_y = 0;     //   (in texel units, offset by one half texel from u = 0)
  int triangle = 0;    // 0: below the diagonal (x,y)-(x+1,y)-(x+1,y+1); 1: the other one
  float u = 0, v = 0;  // Embree barycentrics in that triangle
  bool near_edge = false;   // a barycentric is within 1e-4 of an edge (ambiguous by rounding)
  bool budget_cut = false;  // no hit within the sideways budget, which ended the ray early
};

// Counters of the work done (relaxed atomics; read after the parallel loop).
struct RayCounters {
  std::atomic<uint64_t> rays{0};      // rays requested
  std::atomic<uint64_t> segments{0};  // Embree casts (a ray may need several, see above)
  std::atomic<uint64_t> packets{0};   // 16-wide Embree calls
  std::atomic<uint64_t> unresolved{0};  // rays cut by the sideways budget without a hit

  // Adds another set of counters (relaxed).
  void add(const RayCounters& other) {
    rays.fetch_add(other.rays.load(), std::memory_order_relaxed);
    segments.fetch_add(other.segments.load(), std::memory_order_relaxed);
    packets.fetch_add(other.packets.load(), std::memory_order_relaxed);
    unresolved.fetch_add(other.unresolved.load(), std::memory_order_relaxed);
  }
};

// How far sideways any ray is followed by default, in tile widths. Within the heights the loader
// accepts (|h| <= 64 tiles) the longest parallax ray goes about 171 tiles sideways (the cap
// cos 0.6 through a 128-tile range), so the budget never changes a parallax table; it can cut
// only visibility rays that skim a tall relief at grazing light: through a 128-tile range, about
// 2 100 tiles at the most grazing bin of a 32^2 grid (cos 0.06) and 16 000 at 256^2 (cos 0.008).
inline constexpr double kMaxSidewaysTiles = 1024.0;

// The neighbourhood both stages use unless told otherwise. A ray descending at the parallax cut
// (cos 0.6) through the whole height range moves range * 4/3 sideways; while that is at most half
// a tile, the tile mesh alone (no instancing, which costs ~15 % of the throughput) is fastest and
// only the few rays that cross its border need a second segment; beyond, ceil(travel) rings up to
// 4 (81 instances), and segments for the rest. Results never depend on this choice, only speed
// does.
int automatic_rings(double height_range);

class PeriodicHeightField {
 public:
  // heights: resolution^2 finite values, row-major (tile-side units). rings >= 0: neighbour tiles
  // replicated on each side (0 = the tile mesh alone). max_sideways_tiles > 0: the sideways budget
  // of every ray (header comment). Throws clothbake::Error(Input) naming the texel for a
  // non-finite height, Error(Internal) if Embree fails or for a budget that is not positive. Not
  // safe to call on untrusted sizes: heights.size() must equal resolution^2 (checked,
  // Error(Internal)).
  PeriodicHeightField(const std::vector<float>& heights, int resolution, int rings,
                      double max_sideways_tiles = kMaxSidewaysTiles);
  ~PeriodicHeightField();
  PeriodicHeightField(const PeriodicHeightField&) = delete;
  PeriodicHeightField& operator=(const PeriodicHeightField&) = delete;

  int resolution() const { return resolution_; }
  int rings() const { return rings_; }
  double max_sideways_tiles() const { return max_sideways_; }
  double z_min() const { return z_min_; }
  double z_max() const { return z_max_; }
  // The mesh's vertex height at texel (x, y), any integers (wrapped): what Embree sees (float).
  float height(long x, long y) const;

  // The visibility rays' origin for texel (x, y): the vertex at the texel centre moved by `offset`
  // (tile-side units) along the unit normal of the height field from central differences.
  Vec3d lifted_surface_point(long x, long y, double offset) const;

  // First hits of a packet: t_hit[i] = ray parameter of the first hit in [0, t_max[i]], or
  // +inf (also for a ray cut by the sideways budget, counted in counters->unresolved). Thread-safe;
  // deterministic (each lane's result depends only on that lane's ray). One rtcIntersect16 per
  // segment round, which is faster than one rtcIntersect1 per ray here and gives the same hits.
  void first_hits(const RayPacket& rays, std::array<double, RayPacket::kWidth>& t_hit,
                  RayCounters* counters = nullptr) const;
  // Occlusion of a packet: occluded[i] = the ray hits the surface within [0, t_max[i]] (false for
  // a ray cut by the sideways budget without a hit, counted in counters->unresolved).
  void occluded(const RayPacket& rays, std::array<bool, RayPacket::kWidth>& occluded,
                RayCounters* counters = nullptr) const;
  // One ray, with the triangle it hit (tests and cross-checks; slow path, one Embree call per
  // segment). A ray cut by the sideways budget without a hit has budget_cut set.
  SurfaceHit first_hit(const Vec3d& origin, const Vec3d& direction, double t_max) const;

  // Half a texel: how far beyond the replicated tiles a segment may go (the mesh overlap covers
  // it).
  double margin() const { return 0.5 / double(resolution_); }

 private:
  // One rtcIntersect16 (first_hit) or rtcOccluded16 per segment round: t_hit[i] = the first
  // hit's parameter, or for occlusion the start of the segment that was blocked; +inf without.
  void cast_packet(const RayPacket& rays, std::array<double, RayPacket::kWidth>& t_hit,
                   RayCounters* counters, bool first_hit) const;
  // t_max shortened to the sideways budget for a ray of direction (dx, dy); *cut is set when it
  // was shortened.
  double budget_t_max(double dx, double dy, double t_max, bool* cut) const;

  int resolution_ = 0;
  int rings_ = 0;
  double z_min_ = 0.0, z_max_ = 0.0;
  double max_sideways_ = kMaxSidewaysTiles;
  std::vector<float> heights_;
  RTCDevice device_ = nullptr;
  RTCScene tile_scene_ = nullptr;  // the tile mesh (instanced when rings > 0)
  RTCScene scene_ = nullptr;       // what rays are cast into
};

}  // namespace clothbake::raycast

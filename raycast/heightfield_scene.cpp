#include "raycast/heightfield_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"
#include "model/tile.hpp"

namespace clothbake::raycast {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A segment that ends at the border of the replicated neighbourhood is continued from this far
// before its end, so that a hit exactly on the border cannot fall between two segments.
constexpr double kSegmentOverlap = 1e-6;
// Bounds the segments of one ray (a ray can cross at most t_max / (tile distance) tiles; this only
// guards against a non-terminating loop on absurd input).
constexpr int kMaxSegments = 1 << 20;

void embree_error(void* /*user*/, RTCError code, const char* message) {
  // Embree reports through this callback; the calling code checks rtcGetDeviceError afterwards.
  (void)code;
  (void)message;
}

void check_device(RTCDevice device, const char* what) {
  RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE)
    throw_internal_error(std::string("Embree failed to ") + what + " (error code " +
                         std::to_string(int(err)) + ")");
}

// Where a segment of a ray starts and how long it may be: the origin wrapped into the centre
// tile, and the distance to the end of the ray or to the border of the neighbourhood.
struct Segment {
  double x, y;
  double length;
  bool ends_at_border;
  long shift_x, shift_y;  // whole tiles subtracted from the origin by the wrap
};

[[gnu::always_inline]] inline Segment make_segment(double ox, double oy, double dx, double dy,
                                                   double t_start, double t_max, int rings,
                                                   double margin) {
  Segment s;
  double px = ox + t_start * dx, py = oy + t_start * dy;
  double fx = std::floor(px), fy = std::floor(py);
  s.shift_x = long(fx);
  s.shift_y = long(fy);
  s.x = px - fx;
  s.y = py - fy;
  // The neighbourhood's mesh covers [-rings - 0.5/N, rings + 1 + 1.5/N]; the margin (half a texel)
  // guarantees that every segment but the last moves the ray at least that far sideways.
  const double lo = -double(rings) - margin, hi = double(rings) + 1.0 + margin;
  const double remaining = t_max - t_start;
  // Most segments end inside the neighbourhood: when the end point is inside by more than any
  // rounding error (guard), the exits below are certainly beyond `remaining`, so the outcome is
  // the same without the divisions (they cost more than Embree's share per ray would suggest).
  const double guard = 1e-9 * (1.0 + std::abs(remaining));
  const double end_x = s.x + remaining * dx, end_y = s.y + remaining * dy;
  if (end_x >= lo + guard && end_x <= hi - guard && end_y >= lo + guard && end_y <= hi - guard) {
    s.ends_at_border = false;
    s.length = remaining;
    return s;
  }
  double exit = kInf;
  if (dx > 0) exit = std::min(exit, (hi - s.x) / dx);
  if (dx < 0) exit = std::min(exit, (s.x - lo) / -dx);
  if (dy > 0) exit = std::min(exit, (hi - s.y) / dy);
  if (dy < 0) exit = std::min(exit, (s.y - lo) / -dy);
  s.ends_at_border = exit < remaining;
  s.length = s.ends_at_border ? exit : remaining;
  return s;
}

double advance_after(const Segment& s) {
  return s.length > 4 * kSegmentOverlap ? s.length - kSegmentOverlap : s.length;
}

}  // namespace

int automatic_rings(double height_range) {
  const double travel = height_range * 4.0 / 3.0;
  if (!(travel > 0.5)) return 0;  // also NaN
  return int(std::min(std::ceil(travel), 4.0));
}

PeriodicHeightField::PeriodicHeightField(const std::vector<float>& heights, int resolution,
                                         int rings, double max_sideways_tiles)
    : resolution_(resolution), rings_(rings), max_sideways_(max_sideways_tiles), heights_(heights) {
  if (!(max_sideways_tiles > 0))
    throw_internal_error("PeriodicHeightField: the sideways budget must be positive");
  if (resolution < 1 || heights.size() != std::size_t(resolution) * std::size_t(resolution))
    throw_internal_error("PeriodicHeightField: height map size does not match the resolution");
  if (rings < 0 || rings > 64) throw_internal_error("PeriodicHeightField: rings out of range");
  z_min_ = kInf;
  z_max_ = -kInf;
  for (int y = 0; y < resolution; ++y)
    for (int x = 0; x < resolution; ++x) {
      float h = heights[std::size_t(y) * resolution + x];
      if (!std::isfinite(h))
        throw_input_error("height map: texel (" + std::to_string(x) + ", " + std::to_string(y) +
                          ") is not a finite number");
      z_min_ = std::min(z_min_, double(h));
      z_max_ = std::max(z_max_, double(h));
    }

  device_ = rtcNewDevice(nullptr);
  if (!device_) throw_internal_error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(device_, embree_error, nullptr);

  // The tile mesh over quads [-1, N] x [-1, N]: vertices [-1, N+1]^2.
  const long n = resolution;
  const long vside = n + 3, qside = n + 2;
  RTCGeometry mesh = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      mesh, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vside * vside));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), std::size_t(2 * qside * qside)));
  check_device(device_, "allocate the height-field mesh");
  for (long vy = -1; vy <= n + 1; ++vy)
    for (long vx = -1; vx <= n + 1; ++vx) {
      std::size_t k = std::size_t((vy + 1) * vside + (vx + 1));
      vertices[3 * k + 0] = float((double(vx) + 0.5) / double(n));
      vertices[3 * k + 1] = float((double(vy) + 0.5) / double(n));
      vertices[3 * k + 2] = height(vx, vy);
    }
  for (long qy = -1; qy <= n; ++qy)
    for (long qx = -1; qx <= n; ++qx) {
      auto vid = [&](long vx, long vy) { return unsigned((vy + 1) * vside + (vx + 1)); };
      unsigned a = vid(qx, qy), b = vid(qx + 1, qy), c = vid(qx + 1, qy + 1), d = vid(qx, qy + 1);
      std::size_t q = std::size_t((qy + 1) * qside + (qx + 1));
      unsigned* t0 = indices + 6 * q;
      t0[0] = a, t0[1] = b, t0[2] = c;  // below the diagonal
      t0[3] = a, t0[4] = c, t0[5] = d;  // above it
    }
  rtcCommitGeometry(mesh);
  // No RTC_SCENE_FLAG_ROBUST: it costs 10-20 % of the packet throughput here and did not change a
  // single hit in the CGAL and brute-force comparisons (tests/raycast); the rare ray that leaks
  // through an edge is detected and cast again by the parallax stage (a leaked visibility ray
  // counts one sample as visible).
  tile_scene_ = rtcNewScene(device_);
  rtcSetSceneBuildQuality(tile_scene_, RTC_BUILD_QUALITY_HIGH);
  rtcAttachGeometry(tile_scene_, mesh);
  rtcReleaseGeometry(mesh);
  rtcCommitScene(tile_scene_);
  check_device(device_, "build the height-field BVH");

  if (rings == 0) {
    scene_ = tile_scene_;
    rtcRetainScene(scene_);
    return;
  }
  scene_ = rtcNewScene(device_);
  for (int ty = -rings; ty <= rings; ++ty)
    for (int tx = -rings; tx <= rings; ++tx) {
      RTCGeometry inst = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(inst, tile_scene_);
      const float xfm[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, float(tx), float(ty), 0};
      rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
      rtcCommitGeometry(inst);
      rtcAttachGeometry(scene_, inst);  // geomID = (ty + rings) * (2 rings + 1) + (tx + rings)
      rtcReleaseGeometry(inst);
    }
  rtcCommitScene(scene_);
  check_device(device_, "build the instance BVH");
}

PeriodicHeightField::~PeriodicHeightField() {
  if (scene_) rtcReleaseScene(scene_);
  if (tile_scene_) rtcReleaseScene(tile_scene_);
  if (device_) rtcReleaseDevice(device_);
}

float PeriodicHeightField::height(long x, long y) const {
  const long n = resolution_;
  return heights_[std::size_t(model::wrap_index(y, n) * n + model::wrap_index(x, n))];
}

double PeriodicHeightField::budget_t_max(double dx, double dy, double t_max, bool* cut) const {
  // |d_xy| t <= budget; a vertical ray (|d_xy| = 0) goes nowhere sideways.
  const double sideways = std::sqrt(dx * dx + dy * dy);
  const double limit = sideways > 0 ? max_sideways_ / sideways : kInf;
  *cut = limit < t_max;
  return *cut ? limit : t_max;
}

Vec3d PeriodicHeightField::lifted_surface_point(long x, long y, double offset) const {
  const double n = resolution_;
  double dhdx = (double(height(x + 1, y)) - double(height(x - 1, y))) * n / 2;
  double dhdy = (double(height(x, y + 1)) - double(height(x, y - 1))) * n / 2;
  Vec3d normal = model::normalize(Vec3d{-dhdx, -dhdy, 1.0});
  return Vec3d{(double(x) + 0.5) / n, (double(y) + 0.5) / n, double(height(x, y))} +
         normal * offset;
}

void PeriodicHeightField::cast_packet(const RayPacket& rays,
                                      std::array<double, RayPacket::kWidth>& t_hit,
                                      RayCounters* counters, bool first_hit) const {
  constexpr int W = RayPacket::kWidth;
  alignas(64) RTCRayHit16 rh;
  alignas(64) int valid[W];
  std::array<double, W> t_start{};
  std::array<Segment, W> seg{};
  std::array<bool, W> active{};
  std::array<int, W> segments_cast{};
  std::array<double, W> t_end{};
  std::array<bool, W> cut{};
  int live = 0;
  for (int i = 0; i < W; ++i) {
    t_hit[i] = kInf;
    active[i] = i < rays.count && rays.t_max[i] > 0;
    if (active[i]) t_end[i] = budget_t_max(rays.dx[i], rays.dy[i], rays.t_max[i], &cut[i]);
    live += active[i];
  }
  uint64_t unresolved = 0;
  if (counters)
    counters->rays.fetch_add(uint64_t(std::max(rays.count, 0)), std::memory_order_relaxed);
  // Occlusion: the default (incoherent) context, not RTC_INTERSECT_CONTEXT_FLAG_COHERENT: with the
  // coherent flag, Embree 3.13.5's AVX-512 packet kernel never returned from rtcOccluded16 on an
  // instanced scene once the process had cast coherent occlusion packets into a scene without
  // instances (rings = 0), e.g. a low fabric baked before a tall one (docs/hardening.md, "The
  // Embree hang"; test Bake.LowAndTallFabricsInOneProcessAllFinish). The incoherent kernel reports
  // the same results and measured 13-38 % more occlusion rays per second here (BM_Visibility).
  // First hits: the coherent context (a packet is 4 x 4 neighbouring texels with one direction):
  // 34-38 % more rays per second than the default one (BM_Parallax, BM_ParallaxStage), the same
  // stored codes on every example fabric (it leaks through a few other triangle edges; leaked
  // rays are cast again below), and no hang in any order of low and tall fabrics.
  // First hits as 16-wide packets measured 28-73 % more rays per second than one rtcIntersect1
  // per ray (docs/raycast.md, "Performance").
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  if (first_hit) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  uint64_t casts = 0, packets = 0;
  while (live > 0) {
    for (int i = 0; i < W; ++i) {
      valid[i] = active[i] ? -1 : 0;
      if (!active[i]) {
        // Embree reads inactive lanes' fields; keep them finite.
        rh.ray.org_x[i] = rh.ray.org_y[i] = rh.ray.org_z[i] = 0.f;
        rh.ray.dir_x[i] = rh.ray.dir_y[i] = 0.f;
        rh.ray.dir_z[i] = 1.f;
        rh.ray.tnear[i] = 0.f;
        rh.ray.tfar[i] = 0.f;
        rh.ray.mask[i] = 0;
        rh.ray.flags[i] = 0;
        rh.ray.time[i] = 0.f;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        continue;
      }
      seg[i] = make_segment(rays.ox[i], rays.oy[i], rays.dx[i], rays.dy[i], t_start[i], t_end[i],
                            rings_, margin());
      rh.ray.org_x[i] = float(seg[i].x);
      rh.ray.org_y[i] = float(seg[i].y);
      rh.ray.org_z[i] = float(rays.oz[i] + t_start[i] * rays.dz[i]);
      rh.ray.dir_x[i] = float(rays.dx[i]);
      rh.ray.dir_y[i] = float(rays.dy[i]);
      rh.ray.dir_z[i] = float(rays.dz[i]);
      rh.ray.tnear[i] = 0.f;
      rh.ray.tfar[i] = float(seg[i].length);
      rh.ray.mask[i] = ~0u;
      rh.ray.flags[i] = 0;
      rh.ray.time[i] = 0.f;
      rh.ray.id[i] = unsigned(i);
      rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
      ++casts;
    }
    ++packets;
    if (first_hit)
      rtcIntersect16(valid, scene_, &context, &rh);
    else
      rtcOccluded16(valid, scene_, &context, &rh.ray);
    for (int i = 0; i < W; ++i) {
      if (!active[i]) continue;
      if (first_hit ? rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID
                    : rh.ray.tfar[i] == -std::numeric_limits<float>::infinity()) {
        // A hit: its parameter (first hits), or the start of the blocked segment (occlusion:
        // Embree marks it with tfar = -inf).
        t_hit[i] = first_hit ? t_start[i] + double(rh.ray.tfar[i]) : t_start[i];
        active[i] = false;
        --live;
      } else if (seg[i].ends_at_border && ++segments_cast[i] < kMaxSegments) {
        t_start[i] += advance_after(seg[i]);
      } else {
        unresolved += cut[i];
        active[i] = false;
        --live;
      }
    }
  }
  if (counters) {
    counters->segments.fetch_add(casts, std::memory_order_relaxed);
    counters->packets.fetch_add(packets, std::memory_order_relaxed);
    counters->unresolved.fetch_add(unresolved, std::memory_order_relaxed);
  }
}

void PeriodicHeightField::first_hits(const RayPacket& rays,
                                     std::array<double, RayPacket::kWidth>& t_hit,
                                     RayCounters* counters) const {
  cast_packet(rays, t_hit, counters, true);
}

void PeriodicHeightField::occluded(const RayPacket& rays,
                                   std::array<bool, RayPacket::kWidth>& occluded,
                                   RayCounters* counters) const {
  std::array<double, RayPacket::kWidth> t_hit;
  cast_packet(rays, t_hit, counters, false);
  for (int i = 0; i < RayPacket::kWidth; ++i)
    occluded[i] = t_hit[i] < kInf;
}

SurfaceHit PeriodicHeightField::first_hit(const Vec3d& origin, const Vec3d& direction,
                                          double t_max) const {
  SurfaceHit result;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  bool cut = false;
  const double t_end = t_max > 0 ? budget_t_max(direction.x, direction.y, t_max, &cut) : t_max;
  result.budget_cut = cut;
  double t_start = 0.0;
  for (int count = 0; count < kMaxSegments && t_max > 0; ++count) {
    Segment s = make_segment(origin.x, origin.y, direction.x, direction.y, t_start, t_end, rings_,
                             margin());
    RTCRayHit rh{};
    rh.ray.org_x = float(s.x);
    rh.ray.org_y = float(s.y);
    rh.ray.org_z = float(origin.z + t_start * direction.z);
    rh.ray.dir_x = float(direction.x);
    rh.ray.dir_y = float(direction.y);
    rh.ray.dir_z = float(direction.z);
    rh.ray.tnear = 0.f;
    rh.ray.tfar = float(s.length);
    rh.ray.mask = ~0u;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      result.hit = true;
      result.budget_cut = false;
      result.t = t_start + double(rh.ray.tfar);
      const long n = resolution_, qside = n + 2;
      long q = long(rh.hit.primID) / 2;
      long tile_x = 0, tile_y = 0;
      if (rings_ > 0 && rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID) {
        long side = 2 * rings_ + 1;
        tile_x = long(rh.hit.instID[0]) % side - rings_;
        tile_y = long(rh.hit.instID[0]) / side - rings_;
      }
      result.quad_x = (q % qside - 1) + (tile_x + s.shift_x) * n;
      result.quad_y = (q / qside - 1) + (tile_y + s.shift_y) * n;
      result.triangle = int(rh.hit.primID % 2);
      result.u = rh.hit.u;
      result.v = rh.hit.v;
      const float e = 1e-4f;
      float w = 1.f - rh.hit.u - rh.hit.v;
      result.near_edge = rh.hit.u < e || rh.hit.v < e || w < e;
      return result;
    }
    if (!s.ends_at_border) break;
    t_start += advance_after(s);
  }
  return result;
}

}  // namespace clothbake::raycast

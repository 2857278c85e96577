#include "tests/raycast/cgal_check.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "common/error.hpp"
#include "model/directions.hpp"
#include "raycast/heightfield_scene.hpp"

namespace clothbake::raycast {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kCgalTiles = 2;  // CGAL triangles cover tiles [-2, 2]^2

struct TestRay {
  Vec3d origin, direction;
  double t_max;
  bool occlusion;  // visibility ray: compare hit/miss within t_max
  std::string label;
};

// Smallest barycentric coordinate of p in triangle t, measured in the xy projection (height-field
// triangles never project to a segment).
double min_barycentric(const Triangle& t, const Point& p) {
  double ax = t[0].x(), ay = t[0].y(), bx = t[1].x(), by = t[1].y(), cx = t[2].x(), cy = t[2].y();
  double det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
  double l1 = ((bx - p.x()) * (cy - p.y()) - (cx - p.x()) * (by - p.y())) / det;
  double l2 = ((cx - p.x()) * (ay - p.y()) - (ax - p.x()) * (cy - p.y())) / det;
  return std::min({l1, l2, 1.0 - l1 - l2});
}

}  // namespace

CrossCheckReport cross_check_with_cgal(const FabricMaps& maps, const CrossCheckSettings& s) {
  const int n = maps.resolution;
  if (n < 1 || maps.height.size() != maps.texel_count())
    throw_input_error("height map: size does not match the resolution");
  PeriodicHeightField field(maps.height, n, s.rings);  // validates the heights
  const double z_min = field.z_min(), z_max = field.z_max(), range = z_max - z_min;

  // The same triangles as the Embree mesh (same float vertex coordinates), tiles [-2, 2]^2.
  std::vector<Triangle> triangles;
  triangles.reserve(std::size_t(2 * n * n) * (2 * kCgalTiles + 1) * (2 * kCgalTiles + 1));
  auto vertex = [&](long vx, long vy, long tx, long ty) {
    double x = double(float((double(vx) + 0.5) / n)) + double(tx);
    double y = double(float((double(vy) + 0.5) / n)) + double(ty);
    return Point(x, y, double(field.height(vx, vy)));
  };
  for (long ty = -kCgalTiles; ty <= kCgalTiles; ++ty)
    for (long tx = -kCgalTiles; tx <= kCgalTiles; ++tx)
      for (long qy = 0; qy < n; ++qy)
        for (long qx = 0; qx < n; ++qx) {
          Point a = vertex(qx, qy, tx, ty), b = vertex(qx + 1, qy, tx, ty);
          Point c = vertex(qx + 1, qy + 1, tx, ty), d = vertex(qx, qy + 1, tx, ty);
          triangles.emplace_back(a, b, c);
          triangles.emplace_back(a, c, d);
        }
  Tree tree(triangles.cbegin(), triangles.cend());

  // Deterministic sample of texels (plain modulo of mt19937_64 output: portable).
  std::mt19937_64 rng(s.seed);
  const double lift = std::max(1e-3 * range, 1e-6);
  const double offset = 0.01 / n;
  std::vector<TestRay> rays;
  model::DirectionGrid<double> cap{s.dirs, s.min_cos}, hemisphere{s.dirs, 0.0};
  for (int k = 0; k < s.texels; ++k) {
    long x = long(rng() % uint64_t(n)), y = long(rng() % uint64_t(n));
    for (int j = 0; j < s.dirs; ++j)
      for (int i = 0; i < s.dirs; ++i) {
        Vec3d o = cap.bin_center(i, j);
        std::ostringstream label;
        label << "parallax texel (" << x << ", " << y << ") dir (" << i << ", " << j << ")";
        rays.push_back({{(x + 0.5) / n, (y + 0.5) / n, z_max + lift},
                        -o,
                        (2 * lift + range) / o.z,
                        false,
                        label.str()});
        Vec3d w = hemisphere.bin_center(i, j);
        Vec3d p = field.lifted_surface_point(x, y, offset);
        std::ostringstream vlabel;
        vlabel << "visibility texel (" << x << ", " << y << ") dir (" << i << ", " << j << ")";
        rays.push_back({p, w, (z_max - p.z) / w.z + 1e-6, true, vlabel.str()});
      }
  }

  CrossCheckReport report;
  for (std::size_t first = 0; first < rays.size(); first += RayPacket::kWidth) {
    // Embree through the bake's packet path, one packet per kind of query.
    RayPacket packet;
    packet.count = int(std::min<std::size_t>(RayPacket::kWidth, rays.size() - first));
    for (int l = 0; l < packet.count; ++l) {
      const TestRay& r = rays[first + l];
      packet.ox[l] = r.origin.x, packet.oy[l] = r.origin.y, packet.oz[l] = r.origin.z;
      packet.dx[l] = r.direction.x, packet.dy[l] = r.direction.y, packet.dz[l] = r.direction.z;
      packet.t_max[l] = r.t_max;
    }
    std::array<double, RayPacket::kWidth> t_hit;
    std::array<bool, RayPacket::kWidth> blocked;
    field.first_hits(packet, t_hit);
    field.occluded(packet, blocked);

    for (int l = 0; l < packet.count; ++l) {
      const TestRay& r = rays[first + l];
      // Skip rays whose sideways travel leaves the CGAL tiles.
      Vec3d end = r.origin + r.direction * r.t_max;
      double lo = -double(kCgalTiles) + 1.0 / n, hi = double(kCgalTiles) + 1.0;
      if (std::min(end.x, r.origin.x) < lo || std::max(end.x, r.origin.x) > hi ||
          std::min(end.y, r.origin.y) < lo || std::max(end.y, r.origin.y) > hi) {
        ++report.skipped;
        continue;
      }
      ++report.rays;
      Kernel::Ray_3 query(Point(r.origin.x, r.origin.y, r.origin.z),
                          Kernel::Vector_3(r.direction.x, r.direction.y, r.direction.z));
      double t_cgal = kInf;
      bool cgal_near_edge = false;
      auto hit = tree.first_intersection(query);
      if (hit) {
        if (const Point* p = boost::get<Point>(&hit->first)) {
          Vec3d q{p->x() - r.origin.x, p->y() - r.origin.y, p->z() - r.origin.z};
          t_cgal = model::dot(q, r.direction);
          cgal_near_edge = min_barycentric(*hit->second, *p) < 1e-4;
        } else {
          t_cgal = 0.0;  // the ray runs inside a triangle's plane: an edge-on, ambiguous case
          cgal_near_edge = true;
        }
        if (t_cgal > r.t_max) t_cgal = kInf;
      }
      bool agree;
      double difference = 0.0;
      double t_embree = r.occlusion ? (blocked[l] ? 0.0 : kInf) : t_hit[l];
      if (r.occlusion) {
        agree = (t_cgal < kInf) == blocked[l];
      } else if (t_cgal < kInf && t_embree < kInf) {
        difference = std::abs(t_cgal - t_embree);
        agree = difference <= s.tolerance;
      } else {
        agree = (t_cgal < kInf) == (t_embree < kInf);
      }
      if (agree) {
        ++report.agreements;
        report.max_difference = std::max(report.max_difference, difference);
        continue;
      }
      SurfaceHit embree_hit = field.first_hit(r.origin, r.direction, r.t_max);
      if (cgal_near_edge || (embree_hit.hit && embree_hit.near_edge)) {
        ++report.near_edge_disagreements;
        continue;
      }
      ++report.disagreements;
      if (report.examples.size() < 8) {
        std::ostringstream what;
        what << r.label << ": embree t=" << t_embree << ", cgal t=" << t_cgal;
        report.examples.push_back(what.str());
      }
    }
  }
  return report;
}

}  // namespace clothbake::raycast

// Cross-check of Embree's hits against an exact-predicate ray cast (CGAL AABB tree over the same
// triangles, Exact_predicates_inexact_constructions_kernel), on a deterministic sample of texels
// and directions of both stages: parallax rays (down from the reference plane along -o, o on the
// 0.6 cap) and visibility rays (up from the surface point). docs/raycast.md, "Cross-checks".
//
// Embree's triangle test is fast but not watertight, so a ray through an edge or a vertex may be
// reported on either neighbour or (rarely) missed; CGAL's predicates are exact, so such a ray is
// decided consistently. A disagreement is "near an edge" when the CGAL hit has a barycentric
// coordinate below 1e-4 or Embree reports one; any other disagreement is a bug.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"

namespace clothbake::raycast {

struct CrossCheckSettings {
  int texels = 64;          // texels sampled (uniformly, seeded)
  int dirs = 8;             // dirs x dirs directions per stage and texel
  double min_cos = 0.6;     // parallax cap
  double tolerance = 1e-4;  // |t_embree - t_cgal| allowed, tile-side units
  uint64_t seed = 1;
  int rings = 1;  // Embree neighbourhood (rays beyond it are cut into segments)
};

struct CrossCheckReport {
  int rays = 0;                       // rays compared (parallax + visibility)
  int agreements = 0;                 // same hit distance within tolerance, or both miss
  int near_edge_disagreements = 0;    // disagreements where a hit is within 1e-4 of an edge
  int disagreements = 0;              // any other: must be zero
  int skipped = 0;                    // rays leaving the CGAL neighbourhood (not compared)
  double max_difference = 0.0;        // largest |t_embree - t_cgal| among agreements
  std::vector<std::string> examples;  // a few disagreements, described
};

// Throws Error(Input) on a non-finite height. Cost: builds an AABB tree of the tile and its
// neighbours (keep N small, e.g. <= 64, in tests).
CrossCheckReport cross_check_with_cgal(const FabricMaps& maps, const CrossCheckSettings& settings);

}  // namespace clothbake::raycast

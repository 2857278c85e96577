// Internal to `report stability` (stability_baked.cpp): the baked cases' fabrics, whose height
// depends on u only, and the parallax depth of such a profile cast directly. Not part of the
// library's API.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"
#include "model/vec.hpp"

namespace clothbake::reports::stability {

using model::Vec3d;

// A fabric whose height depends on u only (h(u) at texel centres), so that the parallax ray of
// every texel can be cast directly along the piecewise-linear profile between texel centres (the
// bake's mesh, raycast/heightfield_scene.hpp, is that profile extruded along v).
// The fabric is `name`, n^2 texels, h in tile widths; `dirs`^2 direction bins for every table and
// `clusters` visibility clusters.
Fabric profile_fabric(const std::string& name, int n, const std::function<double(double)>& h,
                      int dirs, int clusters);

// r of the parallax stage (raycast/parallax.cpp) for texel x of a u-only profile, cast directly:
// the ray leaves the texel centre at z_max + lift along -o; the surface between texel centres
// k + 1/2 and k + 3/2 (texel units, wrapped) is linear; r = -clamp(z_max - z_hit, 0, range).
// h: the height of each texel column (tile widths), o: the (unit) outgoing direction.
double direct_depth(const std::vector<double>& h, int x, const Vec3d& o);

}  // namespace clothbake::reports::stability

// Summary statistics of a fabric's feature maps (what `clothbake inspect` prints).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "fabric/fabric.hpp"

namespace clothbake::inputs {

// Range, mean and population standard deviation of one channel (accumulated in double).
struct ChannelStats {
  double min = 0, max = 0, mean = 0, stddev = 0;
};

ChannelStats channel_stats(const std::vector<float>& values);
// Channel c (0..2) of a vector map.
ChannelStats channel_stats(const std::vector<Vec3f>& values, int c);

// Directional statistics of a unit tangent field. Tangents are lines (t and -t are the same fibre
// direction), so angles are averaged as axial data: the mean in-plane direction is half the angle
// of the mean of (cos 2 phi, sin 2 phi) weighted by the in-plane length.
struct TangentStats {
  double mean_abs_z = 0;           // mean |t.z|: how steeply fibres leave the surface
  double mean_elevation_deg = 0;   // mean asin|t.z|
  double fraction_along_x = 0;     // |t.x| > |t.y|: fibres running along u (weft direction)
  double fraction_along_y = 0;     // |t.y| > |t.x|: along v (warp direction); ties count in neither
  double mean_axis_deg = 0;        // axial mean in-plane direction, degrees from +x in (-90, 90]
  double axial_concentration = 0;  // |mean of (cos 2 phi, sin 2 phi)|, 0 = isotropic, 1 = aligned
};

TangentStats tangent_stats(const std::vector<Vec3f>& tangents);

struct MapStats {
  int resolution = 0;
  ChannelStats height;
  std::array<ChannelStats, 3> tangent, normal, albedo;
  ChannelStats gap;
  double gap_fraction = 0;  // fraction of texels with I < 0.5 (gaps)
  TangentStats tangent_directions;
  double mean_normal_tilt_deg = 0;       // mean acos(n.z)
  std::vector<std::size_t> yarn_texels;  // texel count per yarn id (size max id + 1)
};

// Statistics of validated maps (every vector of size resolution^2).
MapStats map_stats(const FabricMaps& maps);

}  // namespace clothbake::inputs

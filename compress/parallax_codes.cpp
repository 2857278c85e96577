// What the parallax compressors share (parallax_codes.hpp).
#include "compress/parallax_codes.hpp"

#include <cmath>

#include "common/error.hpp"
#include "model/directions.hpp"

namespace clothbake::compress {

std::vector<double> parallax_offset_per_depth(int resolution, int dirs, double min_cos) {
  const model::DirectionGrid<double> grid{dirs, min_cos};
  std::vector<double> out(std::size_t(dirs) * dirs);
  for (int j = 0; j < dirs; ++j)
    for (int i = 0; i < dirs; ++i) {
      const model::Vec3d o = grid.bin_center(i, j);
      out[std::size_t(grid.bin_index(i, j))] =
          double(resolution) * std::sqrt(o.x * o.x + o.y * o.y) / o.z;
    }
  return out;
}

void check_parallax_compression_input(const ParallaxCodes& raw, double max_error) {
  if (raw.codes == nullptr || raw.resolution < 1 || raw.dirs < 1)
    throw_input_error("parallax compression: empty parallax table");
  if (!(max_error > 0.0 && max_error <= 1.0))
    throw_input_error("bake.parallax_max_error = " + std::to_string(max_error) +
                      " is out of range; valid range is (0, 1]");
}

}  // namespace clothbake::compress

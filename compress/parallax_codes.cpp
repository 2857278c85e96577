// 8-bit per-direction requantisation of the parallax table (parallax_codes.hpp).
#include "compress/parallax_codes.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/error.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/writer/asset_writer.hpp"
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

QuantisedParallax quantise_parallax(const ParallaxCodes& raw, double max_error) {
  const auto start = std::chrono::steady_clock::now();
  check_parallax_compression_input(raw, max_error);
  const std::size_t texels = std::size_t(raw.resolution) * raw.resolution;
  const std::size_t d = std::size_t(raw.dirs) * raw.dirs;
  const double levels = double((1u << reader::kCompressedParallaxBits) - 1);
  const std::vector<double> per_depth =
      parallax_offset_per_depth(raw.resolution, raw.dirs, raw.min_cos);
  QuantisedParallax p;
  p.resolution = raw.resolution;
  p.dirs = raw.dirs;
  p.min_cos = raw.min_cos;
  p.reference_height = raw.reference_height;
  p.max_offset = raw.max_offset;
  p.steps.assign(d, 0.0);
  p.codes.assign(d * texels, 0);
  double sum2 = 0.0;
  uint64_t above = 0;
  for (std::size_t e = 0; e < d; ++e) {
    const uint16_t* src = raw.codes + e * texels;
    const uint16_t top = *std::max_element(src, src + texels);
    if (top == 0) continue;                     // step 0, codes 0: exactly r = 0
    const double ratio = double(top) / levels;  // raw codes per 8-bit code
    p.steps[e] = raw.depth_scale * ratio;
    uint8_t* dst = p.codes.data() + e * texels;
    for (std::size_t t = 0; t < texels; ++t) {
      const double q = std::min(levels, std::nearbyint(double(src[t]) / ratio));
      dst[t] = uint8_t(q);
      const double depth_error = std::fabs(q * p.steps[e] - double(src[t]) * raw.depth_scale);
      const double offset_error = depth_error * per_depth[e];
      sum2 += offset_error * offset_error;
      p.max_depth_error = std::max(p.max_depth_error, depth_error);
      p.max_offset_error = std::max(p.max_offset_error, offset_error);
      if (offset_error > 0.25) ++above;
    }
  }
  const double entries = double(texels) * double(d);
  p.rms_offset_error = std::sqrt(sum2 / entries);
  p.share_above_quarter = double(above) / entries;
  p.rms_offset_error_8bit = p.rms_offset_error;
  if (p.rms_offset_error > max_error) {  // 16 bits: the raw codes, exactly
    p.bits = 16;
    std::vector<uint8_t>().swap(p.codes);
    p.codes16.assign(raw.codes, raw.codes + d * texels);
    for (std::size_t e = 0; e < d; ++e) {
      const uint16_t* src = raw.codes + e * texels;
      p.steps[e] = *std::max_element(src, src + texels) ? raw.depth_scale : 0.0;
    }
    p.rms_offset_error = p.max_offset_error = p.share_above_quarter = p.max_depth_error = 0.0;
  }
  p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return p;
}

std::vector<formats::Section> compressed_parallax_sections(const QuantisedParallax& p) {
  const uint32_t n = uint32_t(p.resolution), d = uint32_t(p.dirs * p.dirs);
  const reader::CompressedParallaxInfoRecord info = parallax_info_record(p, uint32_t(p.bits), 0u);
  std::vector<formats::Section> out;
  out.push_back(formats::make_record_section(
      reader::SectionType::ParallaxCompressed, reader::kCompressedParallaxInfoInstance,
      std::span<const reader::CompressedParallaxInfoRecord>(&info, 1)));
  out.push_back(formats::make_array_section<double>(reader::SectionType::ParallaxCompressed,
                                                    reader::kCompressedParallaxStepsInstance,
                                                    p.steps, {d}));
  if (p.bits == 8)
    out.push_back(formats::make_array_section<uint8_t>(reader::SectionType::ParallaxCompressed,
                                                       reader::kCompressedParallaxCodesInstance,
                                                       p.codes, {d, n, n}));
  else
    out.push_back(formats::make_array_section<uint16_t>(reader::SectionType::ParallaxCompressed,
                                                        reader::kCompressedParallaxCodesInstance,
                                                        p.codes16, {d, n, n}));
  return out;
}

}  // namespace clothbake::compress

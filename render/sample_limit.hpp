// The largest render a command accepts: footprint samples one render pass may ask for per light,
// image pixels x spp, at most 2^36 (about 7.6 hours on one core at the 0.4 us per sample measured
// on a small asset, more with environment lights; docs/rendering.md, "Bounds"), checked before
// anything is loaded.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "common/error.hpp"

namespace clothbake::render {

inline constexpr double kMaxRenderSamplesPerPass = 68719476736.0;  // 2^36

// Throws Error(Usage) naming `option` ("--spp: 300 samples per pixel at ...") when width x height
// x spp exceeds kMaxRenderSamplesPerPass.
inline void check_render_samples(int width, int height, uint64_t spp, const std::string& option) {
  const double samples = double(width) * double(height) * double(spp);
  if (samples <= kMaxRenderSamplesPerPass) return;
  char text[96];
  std::snprintf(text, sizeof text, "%.3g footprint samples per light and pass; at most 2^36 (%.3g",
                samples, kMaxRenderSamplesPerPass);
  throw Error(ExitCode::Usage, option + ": " + std::to_string(spp) + " samples per pixel at " +
                                   std::to_string(width) + "x" + std::to_string(height) +
                                   " pixels ask for " + text +
                                   ", hours on one core) are accepted: lower it or the image size");
}

}  // namespace clothbake::render

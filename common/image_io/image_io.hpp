// Image reading and writing through OpenImageIO: EXR, PNG, TIFF (and anything else OIIO reads),
// 8-bit, 16-bit or float, 1-4 channels. Pixels are converted to float on read; 8/16-bit integer
// images are normalised to [0, 1] (OIIO's convention), with no colour-space conversion.
#pragma once

#include <cstdint>

#include <cstddef>
#include <string>
#include <vector>

namespace clothbake {

// A float image, row-major, interleaved channels: value(x, y, c) = pixels[(y * width + x) *
// channels + c]. Row 0 is the top row of the file.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;
  std::string source_format;     // e.g. "openexr", "png", "tiff"; empty for in-memory images
  int source_bits = 0;           // bits per channel in the file (8, 16, 32)
  bool source_is_float = false;  // the file stores floating-point (half/float) pixels

  Image() = default;
  Image(int w, int h, int c)
      : width(w), height(h), channels(c), pixels(std::size_t(w) * h * c, 0.f) {}
  float& at(int x, int y, int c) { return pixels[(std::size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const {
    return pixels[(std::size_t(y) * width + x) * channels + c];
  }
};

// What read_image accepts beyond its defaults; every limit is checked from the file's header,
// before any pixel memory is allocated.
struct ImageReadLimits {
  int max_side = 0;         // width and height at most this; 0: no limit
  uint64_t max_pixels = 0;  // width x height at most this; 0: no limit
  int first_channels = 0;   // 0: every channel (1 to 4); N: only the first N, a file needs >= N
};

// Reads an image file. Throws clothbake::Error(Input) naming the path when the file is missing,
// unreadable, truncated, empty (zero size), has more than 4 channels (unless first_channels picks
// fewer) or fewer than first_channels, or is larger than `limits` allows.
Image read_image(const std::string& path, const ImageReadLimits& limits = {});

enum class PixelType { Float32, Half, UInt8, UInt16 };

// Writes an image; the format follows the extension (.exr, .png, .tif/.tiff). For integer outputs
// values are clamped to [0, 1] and quantised. Throws clothbake::Error(Input) on I/O failure.
// Writes to PATH directly: callers that need atomicity write to a temporary name and rename.
void write_image(const std::string& path, const Image& image, PixelType type);

}  // namespace clothbake

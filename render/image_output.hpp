// The renderer's image files: a linear float EXR and an sRGB 8-bit PNG preview beside it, written
// through OpenImageIO to temporary names that are renamed only when both are complete.
#pragma once

#include <filesystem>
#include <string>

#include "common/image_io/image_io.hpp"
#include "render/renderer.hpp"

namespace clothbake::render {

struct OutputFiles {
  std::string exr, png;
};

// Checks an output path before any work: it must end in .exr, not be a directory, and its folder
// must exist or be creatable (its nearest existing ancestor a folder; write_render_images creates
// it). Throws clothbake::Error(Input) naming the path.
void check_output_path(const std::string& exr_path);

// Creates exr_path's folder when missing, then writes exr_path (linear radiance, as rendered) and
// the same path with .png (preview_value of each channel). Throws clothbake::Error(Input) on I/O
// failure, leaving neither file changed.
OutputFiles write_render_images(const std::string& exr_path, const RenderResult& image,
                                const Preview& preview = {});

// The PNG preview's display value in [0, 1] of pixel `rgb` (linear radiance, any floats; NaN and
// negative values give 0): scaled by 2^exposure, tone mapped (scene.hpp, ToneMap), sRGB-encoded.
void preview_value(const float rgb[3], const Preview& preview, float out[3]);

// The preview of a whole render: preview_value of every pixel (values in [0, 1], 3 channels), the
// image the PNGs of `render` and the reports hold. Allocates the image.
Image preview_image(const RenderResult& image, const Preview& preview);

// Writes `image` to `path` through OpenImageIO (the format from the extension) under a temporary
// name (formats::TempFile: locked, removed on a signal, stale ones of a killed writer removed
// first) renamed when complete. Throws clothbake::Error(Input) naming the path; `path` is then
// unchanged.
void write_image_atomically(const std::filesystem::path& path, const Image& image, PixelType type);

// The sRGB transfer function of a linear value, clamped to [0, 1].
double srgb_encode(double linear);

}  // namespace clothbake::render

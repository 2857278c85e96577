// EXR and PNG outputs of a render (image_output.hpp).
#include "render/image_output.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::render {
namespace fs = std::filesystem;

double srgb_encode(double v) {
  if (!(v > 0)) return 0;
  if (v >= 1) return 1;
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}

void preview_value(const float rgb[3], const Preview& preview, float out[3]) {
  const double scale = std::exp2(preview.exposure);
  double c[3];
  for (int k = 0; k < 3; ++k) {
    const double v = double(rgb[k]) * scale;
    c[k] = v > 0 ? v : 0.0;  // NaN and negative values show black
  }
  switch (preview.tone_map) {
    case ToneMap::Clamp:
      break;
    case ToneMap::Reinhard: {
      // On the luminance, so that a bright colour keeps its hue until a channel clips.
      const double l = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
      if (l > 0 && std::isfinite(l))
        for (double& v : c)
          v *= 1.0 / (1.0 + l);
      break;
    }
    case ToneMap::Filmic:
      for (double& v : c)
        v = std::isfinite(v) ? (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14) : 1.0;
      break;
  }
  for (int k = 0; k < 3; ++k)
    out[k] = float(srgb_encode(c[k]));
}

Image preview_image(const RenderResult& r, const Preview& preview) {
  Image shown(r.width, r.height, 3);
  for (std::size_t k = 0; k + 2 < r.rgb.size(); k += 3)
    preview_value(&r.rgb[k], preview, &shown.pixels[k]);
  return shown;
}

void check_output_path(const std::string& exr_path) {
  const fs::path p(exr_path);
  if (p.extension() != ".exr")
    throw_input_error(exr_path +
                      ": the output must be an .exr file (a .png preview is written "
                      "beside it)");
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw_input_error(exr_path + ": is a directory");
  // A missing folder is created when the images are written (not now: a render that fails
  // leaves nothing behind).
  formats::check_creatable_folder(p.parent_path(), exr_path);
}

void write_image_atomically(const fs::path& path, const Image& image, PixelType type) {
  // The extension stays last: OpenImageIO picks the format by it.
  formats::TempFile tmp(path, path.extension().string());
  write_image(tmp.path().string(), image, type);
  tmp.commit();
}

OutputFiles write_render_images(const std::string& exr_path, const RenderResult& r,
                                const Preview& preview) {
  OutputFiles files;
  files.exr = exr_path;
  files.png = fs::path(exr_path).replace_extension(".png").string();
  if (const fs::path dir = fs::path(exr_path).parent_path(); !dir.empty()) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw_input_error(exr_path + ": cannot create its folder (" + ec.message() + ")");
  }
  Image linear(r.width, r.height, 3);
  std::copy(r.rgb.begin(), r.rgb.end(), linear.pixels.begin());
  const Image shown = preview_image(r, preview);
  // formats::TempFile: locked, registered for the signal handlers, and any stale temporaries of a
  // killed render are removed first. The extension stays last: OpenImageIO picks the format by it.
  formats::TempFile exr_tmp(files.exr, ".exr"), png_tmp(files.png, ".png");
  write_image(exr_tmp.path().string(), linear, PixelType::Float32);
  write_image(png_tmp.path().string(), shown, PixelType::UInt8);
  exr_tmp.commit();
  png_tmp.commit();
  return files;
}

}  // namespace clothbake::render

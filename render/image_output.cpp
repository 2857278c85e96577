// EXR and PNG outputs of a render (image_output.hpp).
#include "render/image_output.hpp"

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

OutputFiles write_render_images(const std::string& exr_path, const RenderResult& r) {
  OutputFiles files;
  files.exr = exr_path;
  files.png = fs::path(exr_path).replace_extension(".png").string();
  if (const fs::path dir = fs::path(exr_path).parent_path(); !dir.empty()) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw_input_error(exr_path + ": cannot create its folder (" + ec.message() + ")");
  }
  Image linear(r.width, r.height, 3), preview(r.width, r.height, 3);
  for (std::size_t k = 0; k < r.rgb.size(); ++k) {
    linear.pixels[k] = r.rgb[k];
    preview.pixels[k] = float(srgb_encode(r.rgb[k]));
  }
  // formats::TempFile: locked, registered for the signal handlers, and any stale temporaries of a
  // killed render are removed first. The extension stays last: OpenImageIO picks the format by it.
  formats::TempFile exr_tmp(files.exr, ".exr"), png_tmp(files.png, ".png");
  write_image(exr_tmp.path().string(), linear, PixelType::Float32);
  write_image(png_tmp.path().string(), preview, PixelType::UInt8);
  exr_tmp.commit();
  png_tmp.commit();
  return files;
}

}  // namespace clothbake::render

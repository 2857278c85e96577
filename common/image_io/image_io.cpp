#include "common/image_io/image_io.hpp"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <filesystem>

#include "common/error.hpp"

namespace clothbake {

Image read_image(const std::string& path, const ImageReadLimits& limits) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw_input_error(fmt::format("{}: file not found", path));
  if (std::filesystem::is_directory(path, ec))
    throw_input_error(fmt::format("{}: is a directory, expected an image file", path));
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::string why = OIIO::geterror();
    throw_input_error(
        fmt::format("{}: cannot read image ({})", path, why.empty() ? "unknown format" : why));
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0)
    throw_input_error(
        fmt::format("{}: image has zero size ({}x{})", path, spec.width, spec.height));
  if (limits.first_channels > 0 && spec.nchannels < limits.first_channels)
    throw_input_error(fmt::format("{}: image has {} channel(s), expected at least {}", path,
                                  spec.nchannels, limits.first_channels));
  if (limits.first_channels == 0 && (spec.nchannels < 1 || spec.nchannels > 4))
    throw_input_error(
        fmt::format("{}: image has {} channels, expected 1 to 4", path, spec.nchannels));
  const uint64_t pixels = uint64_t(spec.width) * uint64_t(spec.height);
  if (limits.max_side > 0 && (spec.width > limits.max_side || spec.height > limits.max_side))
    throw_input_error(fmt::format("{}: image is {}x{}; at most {} pixels a side are accepted", path,
                                  spec.width, spec.height, limits.max_side));
  if (limits.max_pixels > 0 && pixels > limits.max_pixels)
    throw_input_error(fmt::format("{}: image is {}x{} ({} pixels); at most {} are accepted", path,
                                  spec.width, spec.height, pixels, limits.max_pixels));
  const int channels = limits.first_channels > 0 ? limits.first_channels : spec.nchannels;
  Image image(spec.width, spec.height, channels);
  image.source_format = in->format_name();
  image.source_bits = int(spec.format.size() * 8);
  image.source_is_float = spec.format.is_floating_point();
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
    std::string why = in->geterror();
    throw_input_error(
        fmt::format("{}: cannot read pixels, file truncated or corrupt ({})", path, why));
  }
  in->close();
  return image;
}

void write_image(const std::string& path, const Image& image, PixelType type) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != std::size_t(image.width) * image.height * image.channels)
    throw_internal_error(fmt::format("write_image({}): inconsistent image dimensions", path));
  OIIO::TypeDesc format = OIIO::TypeDesc::FLOAT;
  switch (type) {
    case PixelType::Float32:
      format = OIIO::TypeDesc::FLOAT;
      break;
    case PixelType::Half:
      format = OIIO::TypeDesc::HALF;
      break;
    case PixelType::UInt8:
      format = OIIO::TypeDesc::UINT8;
      break;
    case PixelType::UInt16:
      format = OIIO::TypeDesc::UINT16;
      break;
  }
  auto out = OIIO::ImageOutput::create(path);
  if (!out)
    throw_input_error(fmt::format("{}: cannot create image writer ({})", path, OIIO::geterror()));
  OIIO::ImageSpec spec(image.width, image.height, image.channels, format);
  // OIIO stamps the current time into EXR/TIFF headers; an empty DateTime keeps the bytes a pure
  // function of the pixels, so generated maps hash the same on every run (asset provenance).
  spec.attribute("DateTime", "");
  if (format == OIIO::TypeDesc::FLOAT || format == OIIO::TypeDesc::HALF)
    spec.attribute("compression", "zip");
  if (!out->open(path, spec))
    throw_input_error(fmt::format("{}: cannot open for writing ({})", path, out->geterror()));
  if (!out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()))
    throw_input_error(fmt::format("{}: cannot write image ({})", path, out->geterror()));
  if (!out->close())
    throw_input_error(fmt::format("{}: cannot finish writing ({})", path, out->geterror()));
}

}  // namespace clothbake

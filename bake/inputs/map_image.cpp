#include "bake/inputs/map_image.hpp"
#include "bake/inputs/fabric_files.hpp"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "common/error.hpp"

namespace clothbake::inputs {
namespace {

struct ChannelRule {
  const char* role;
  std::vector<int> accepted;
  const char* what;  // for the message
};

const std::vector<ChannelRule>& channel_rules() {
  static const std::vector<ChannelRule> rules = {
      {"height", {1}, "1 channel (greyscale)"},
      {"tangent", {3, 4}, "3 channels (XYZ; a 4th alpha channel is ignored)"},
      {"normal", {3, 4}, "3 channels (XYZ; a 4th alpha channel is ignored)"},
      {"gap", {1}, "1 channel (greyscale)"},
      {"yarn_id", {1}, "1 channel (greyscale)"},
      {"albedo", {1, 3, 4}, "1 channel (grey), 3 (RGB) or 4 (RGBA, alpha ignored)"},
  };
  return rules;
}

const ChannelRule& rule_for(const std::string& role) {
  for (const auto& r : channel_rules())
    if (role == r.role) return r;
  throw_internal_error("read_map_image: unknown map role '" + role + "'");
}

// Header facts read before the pixels: the stored pixel type (read_image converts to float and
// loses it) and the size, checked before anything proportional to it is allocated.
struct StoredType {
  bool readable = false;  // false: leave the diagnosis to read_image
  int width = 0, height = 0;
  bool unsigned_integer = false;
  bool signed_integer = false;
  int bits = 32;
};

StoredType probe_stored_type(const std::string& path) {
  StoredType t;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return t;
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    OIIO::geterror();  // clear it; read_image reports the failure with its own message
    return t;
  }
  t.readable = true;
  t.width = in->spec().width;
  t.height = in->spec().height;
  OIIO::TypeDesc format = in->spec().format;
  t.bits = int(format.size() * 8);
  if (!format.is_floating_point()) {
    bool is_signed =
        format.basetype == OIIO::TypeDesc::INT8 || format.basetype == OIIO::TypeDesc::INT16 ||
        format.basetype == OIIO::TypeDesc::INT32 || format.basetype == OIIO::TypeDesc::INT64;
    t.signed_integer = is_signed;
    t.unsigned_integer = !is_signed;
  }
  in->close();
  return t;
}

[[noreturn]] void pixel_error(const MapImage& map, int x, int y, const std::string& what) {
  throw Error(ExitCode::Input, fmt::format("{}: pixel ({}, {}) {}", map.context, x, y, what));
}

// Checks the first `used` channels of every pixel for NaN/Inf.
void check_finite(const MapImage& map, int used) {
  const Image& im = map.image;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      for (int c = 0; c < used; ++c) {
        float v = im.at(x, y, c);
        if (!std::isfinite(v))
          pixel_error(map, x, y,
                      fmt::format("channel {} is {}", c, std::isnan(v) ? "NaN" : "infinite"));
      }
}

std::vector<Vec3f> decode_vectors(const MapImage& map, bool is_normal) {
  check_finite(map, 3);
  const Image& im = map.image;
  const char* noun = is_normal ? "normal" : "tangent";
  std::vector<Vec3f> out(std::size_t(im.width) * im.height);
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      double v[3];
      for (int c = 0; c < 3; ++c) {
        double p = im.at(x, y, c);
        v[c] = map.integer_encoded ? 2.0 * p - 1.0 : p;
      }
      double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      if (len < kMinVectorLength)
        pixel_error(map, x, y,
                    fmt::format("has a zero-length {} ({:.4g}, {:.4g}, {:.4g}): length {:.3g} < {}",
                                noun, v[0], v[1], v[2], len, kMinVectorLength));
      // Vectors that are already unit to float precision are kept bit for bit (so that maps
      // written by `clothbake pattern` load back unchanged); others are normalised.
      if (std::abs(len - 1.0) <= 1e-6) len = 1.0;
      Vec3f unit{float(v[0] / len), float(v[1] / len), float(v[2] / len)};
      if (is_normal && !(unit[2] > 0.f))
        pixel_error(map, x, y,
                    fmt::format("has a normal ({:.4g}, {:.4g}, {:.4g}) that does not point up "
                                "(z <= 0); normals are in the local frame, +z = macro normal",
                                unit[0], unit[1], unit[2]));
      out[std::size_t(y) * im.width + x] = unit;
    }
  return out;
}

}  // namespace

int map_image_side(const std::string& path) {
  const StoredType t = probe_stored_type(path);
  return t.readable ? t.width : 0;
}

MapImage read_map_image(const std::string& path, const std::string& role,
                        const std::string& key_context) {
  const ChannelRule& rule = rule_for(role);
  MapImage map;
  map.role = role;
  map.path = path;
  map.context = fmt::format("{}: {}", key_context, path);
  const std::string& context = map.context;
  require_regular_file(path, key_context);  // no FIFO, /dev/zero or /dev/urandom as a map
  StoredType stored = probe_stored_type(path);
  if (stored.readable && (stored.width > kMaxMapSide || stored.height > kMaxMapSide))
    throw Error(ExitCode::Input,
                fmt::format("{}: image is {}x{}; map resolution must be at most {}", context,
                            stored.width, stored.height, kMaxMapSide));
  try {
    map.image = read_image(path);  // its messages start with the path
  } catch (const Error& e) {
    throw Error(e.code(), fmt::format("{}: {}", key_context, e.what()));
  }
  const Image& im = map.image;
  bool accepted = false;
  for (int n : rule.accepted)
    accepted = accepted || im.channels == n;
  if (!accepted)
    throw Error(ExitCode::Input,
                fmt::format("{}: image has {} channel{}; a {} map needs {}", context, im.channels,
                            im.channels == 1 ? "" : "s", role, rule.what));
  if (im.width != im.height)
    throw Error(ExitCode::Input,
                fmt::format("{}: image is {}x{}; feature maps must be square (one N x N tile)",
                            context, im.width, im.height));
  map.integer_encoded = stored.unsigned_integer;
  map.bits = stored.bits;
  return map;
}

std::vector<float> decode_height(const MapImage& map, double scale) {
  check_finite(map, 1);
  const Image& im = map.image;
  std::vector<float> out(std::size_t(im.width) * im.height);
  for (std::size_t i = 0; i < out.size(); ++i) {
    double h = double(im.pixels[i]) * scale;
    if (!std::isfinite(float(h)))
      pixel_error(map, int(i % im.width), int(i / im.width),
                  fmt::format("height {} times scale {} overflows a float", im.pixels[i], scale));
    out[i] = float(h);
  }
  return out;
}

std::vector<Vec3f> decode_tangents(const MapImage& map) {
  return decode_vectors(map, false);
}
std::vector<Vec3f> decode_normals(const MapImage& map) {
  return decode_vectors(map, true);
}

std::vector<float> decode_gap(const MapImage& map) {
  check_finite(map, 1);
  const Image& im = map.image;
  std::vector<float> out(std::size_t(im.width) * im.height);
  for (std::size_t i = 0; i < out.size(); ++i) {
    float g = im.pixels[i];
    if (g < 0.f || g > 1.f)
      pixel_error(map, int(i % im.width), int(i / im.width),
                  fmt::format("has gap value {}, outside [0, 1] (1 = yarn, 0 = gap)", g));
    out[i] = g;
  }
  return out;
}

std::vector<uint16_t> decode_yarn_ids(const MapImage& map) {
  check_finite(map, 1);
  const Image& im = map.image;
  // OIIO maps unsigned integers to p / (2^bits - 1); undo it exactly (double has room).
  double to_id = 1.0;
  if (map.integer_encoded) to_id = std::ldexp(1.0, map.bits) - 1.0;
  std::vector<uint16_t> out(std::size_t(im.width) * im.height);
  for (std::size_t i = 0; i < out.size(); ++i) {
    double v = double(im.pixels[i]) * to_id;
    double id = std::round(v);
    int x = int(i % im.width), y = int(i / im.width);
    if (std::abs(v - id) > 1e-3)
      pixel_error(map, x, y,
                  fmt::format("has yarn id {}, which is not an integer (a float yarn_id map stores "
                              "the ids themselves: 0, 1, 2, ...)",
                              v));
    if (id < 0 || id > 65535)
      pixel_error(map, x, y, fmt::format("has yarn id {}, outside [0, 65535]", id));
    out[i] = uint16_t(id);
  }
  return out;
}

std::vector<Vec3f> decode_albedo(const MapImage& map, bool srgb) {
  const Image& im = map.image;
  int used = im.channels == 1 ? 1 : 3;
  check_finite(map, used);
  std::vector<Vec3f> out(std::size_t(im.width) * im.height);
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      Vec3f rgb{};
      for (int c = 0; c < 3; ++c) {
        float v = im.at(x, y, used == 1 ? 0 : c);
        if (v < 0.f || v > 1.f)
          pixel_error(map, x, y, fmt::format("channel {} has albedo {}, outside [0, 1]", c, v));
        rgb[c] = srgb ? float(srgb_to_linear(v)) : v;
      }
      out[std::size_t(y) * im.width + x] = rgb;
    }
  return out;
}

double srgb_to_linear(double e) {
  return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

double linear_to_srgb(double l) {
  if (l <= 0.0) return 0.0;
  if (l >= 1.0) return 1.0;
  return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

}  // namespace clothbake::inputs

// Feature maps from image files: reading through common/image_io/image_io.hpp (OpenImageIO), the
// channel rules per map, decoding of the stored values and per-pixel validation
// (docs/fabric-format.md, "Map conventions").
//
//  map      channels            stored value -> decoded value
//  height   1                   h (any finite value) * scale
//  tangent  3, or 4 (A ignored) float image: v in [-1, 1]; 8/16-bit image: v = 2 p - 1; normalised
//  normal   3, or 4 (A ignored) as tangent; must point up (z > 0) after normalisation
//  gap      1                   I in [0, 1] (1 = yarn, 0 = gap)
//  yarn_id  1                   float image: the integer id itself; 8/16-bit: p * (2^bits - 1)
//  albedo   1 (grey), 3, or 4   linear RGB in [0, 1], optionally sRGB-decoded
//
// Safe on untrusted input: every problem throws clothbake::Error(ExitCode::Input) with a message
// that starts with the caller's context (the TOML file and key) and names the image file and, for
// bad values, the pixel (x, y) with x to the right and y down from the top row of the file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/image_io/image_io.hpp"
#include "fabric/fabric.hpp"

namespace clothbake::inputs {

// Tangents or normals shorter than this after decoding are rejected as zero-length (an 8-bit
// encoding of the zero vector decodes to length < 0.007; a quantised unit vector to ~1 +- 0.01).
inline constexpr float kMinVectorLength = 0.01f;

// Largest map side read_map_image accepts; checked from the file header before the pixels are
// allocated, so a hostile header cannot ask for gigabytes (fabric_load's kMaxResolution).
inline constexpr int kMaxMapSide = 8192;

// One map image as read from disk.
struct MapImage {
  std::string role;     // "height", "tangent", ... (the key in [maps])
  std::string path;     // resolved path of the image file
  std::string context;  // message prefix for pixels, e.g. "fabric.toml:3:10: maps.height: /d/h.png"
  Image image;
  bool integer_encoded = false;  // 8/16-bit integer pixels (normalised to [0, 1] by OIIO)
  int bits = 32;                 // bits per channel in the file
};

// Reads the image at `path` for map `role` and checks its channel count against the table above.
// `key_context` (the TOML file, line and key) prefixes every message, followed by the image path.
// Throws Error(Input) for a missing, unreadable or truncated file, a wrong channel count, a
// zero-size or non-square image, or one with a side above kMaxMapSide (checked from the header).
MapImage read_map_image(const std::string& path, const std::string& role,
                        const std::string& key_context);

// The width of the image at `path` from its header (no pixel read), or 0 when it is not a
// readable regular file. For estimates before loading; read_map_image does the checks.
int map_image_side(const std::string& path);

// Decoders: each checks every pixel it uses (NaN/Inf, range, zero length, non-integer id) and
// throws Error(Input) naming the pixel. Output is row-major, resolution^2 entries.
std::vector<float> decode_height(const MapImage& map, double scale);
std::vector<Vec3f> decode_tangents(const MapImage& map);
std::vector<Vec3f> decode_normals(const MapImage& map);
std::vector<float> decode_gap(const MapImage& map);
std::vector<uint16_t> decode_yarn_ids(const MapImage& map);
std::vector<Vec3f> decode_albedo(const MapImage& map, bool srgb);

// The sRGB electro-optical transfer function (IEC 61966-2-1): encoded [0, 1] -> linear [0, 1].
double srgb_to_linear(double encoded);
// Its inverse: linear [0, 1] -> encoded [0, 1] (used for PNG previews).
double linear_to_srgb(double linear);

}  // namespace clothbake::inputs

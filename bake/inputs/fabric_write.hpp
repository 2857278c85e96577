// Writing a fabric's maps to a directory (what `clothbake pattern` produces): float EXR maps,
// 8-bit PNG previews, and a fabric.toml that refers to the EXR maps with every parameter, so that
// the written fabric can be edited and baked and loads back to the same maps.
#pragma once

#include <string>
#include <vector>

#include "common/image_io/image_io.hpp"
#include "fabric/fabric.hpp"

namespace clothbake {

struct WrittenFile {
  std::string role;  // "height", ..., "height_preview", ..., "fabric"
  std::string path;  // final path inside the output directory
};

// Writes into a temporary directory next to `dir` and moves the files into `dir` only when all of
// them were written: on any failure nothing appears at `dir` (the temporary directory, and any
// parent directories this call created, are removed), and files already in an existing `dir` that
// are not among the outputs are left alone (outputs of the same name are replaced). `comment` is
// put at the top of fabric.toml (e.g. where the fabric came from). Throws Error(Input) on I/O
// errors or when `dir` exists and is not a directory; Error(Internal) for maps that are not
// resolution^2 in size. Returns the files written, in a fixed order.
std::vector<WrittenFile> write_fabric_directory(const Fabric& fabric, const std::string& dir,
                                                const std::string& comment);

// The fabric.toml text write_fabric_directory writes (maps named "<role>.exr" beside it).
std::string fabric_toml_text(const Fabric& fabric, const std::string& comment);

// 8-bit previews: tangent/normal as 0.5 v + 0.5, height normalised to its [min, max] (0.5 when
// constant), gap as grey, yarn id in distinct colours (yarn_id_color), albedo sRGB-encoded.
Image preview_image(const FabricMaps& maps, const std::string& role);

// A distinct, saturated display colour per yarn id (golden-ratio hue steps), each channel in [0,
// 1].
Rgb yarn_id_color(unsigned id);

// TOML basic string literal for `text` (quotes added; ", \ and control characters escaped).
std::string toml_quote(const std::string& text);

}  // namespace clothbake

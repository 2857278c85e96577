// Loading a fabric description (TOML, docs/fabric-format.md) into a validated Fabric: feature maps
// from image files or from a procedural weave / WIF draft, yarn materials, sheen, bake settings
// (defaults from the paper), physical units converted to tile-side units, and the XXH64 content
// hash of every file read.
//
// Safe on untrusted input: every bad file, key, value or pixel throws clothbake::Error with
// ExitCode::Input and a message naming the TOML file and the key (with line and column) or the
// image file and pixel; nothing is written anywhere. Warnings (a constant height map, an unused
// yarn, WIF oddities) go through clothbake::warn().
#pragma once

#include <optional>
#include <string>

#include "bake/inputs/weave_maps.hpp"
#include "fabric/fabric.hpp"

namespace clothbake {

// Where the feature maps of a fabric came from.
enum class FabricSource { Images, NamedWeave, MatrixWeave, Wif };

// "images", "named_weave", "matrix_weave", "wif".
const char* fabric_source_name(FabricSource source);

struct LoadedFabric {
  Fabric fabric;
  FabricSource source = FabricSource::Images;
  // Weave sources: the resolved spec the maps were generated from (matrix, per-thread colours in
  // linear RGB, yarn geometry in mm). Empty for image fabrics.
  std::optional<weave::WeaveSpec> weave;
  std::string weave_label;  // "twill2/1", "matrix", or the WIF title (else its file name)
};

// The resolution of a weave's maps when nothing else gives one (pattern --weave/--wif, a WIF draft
// given as a fabric).
inline constexpr int kDefaultWeaveResolution = 256;

struct LoadOptions {
  // Overrides [bake] resolution (pattern --resolution). Weaves are generated at this resolution;
  // image fabrics must already have it (maps are never resampled), else Error(Input).
  std::optional<int> resolution;
};

// Loads and validates the fabric description at `toml_path`. Relative paths in it resolve against
// the TOML file's directory. Fabric::inputs lists the TOML file first ("fabric"), then every image
// or WIF file read, each with its XXH64 content hash. A WIF draft (a ".wif" name, or a "[WIF]"
// section) is read as fabric_from_wif does, at options.resolution or kDefaultWeaveResolution, with
// the [bake] defaults and automatic half-vector bins (docs/weaves.md, "WIF drafts as fabrics"). A
// scene or an asset is refused as such (Error(Input) "PATH is a scene, not a fabric
// description: ..."), before any TOML error.
LoadedFabric load_fabric_description(const std::string& toml_path, const LoadOptions& options = {});

// What the up-front memory estimate needs to know of a fabric before anything is decoded.
struct FabricSettingsPeek {
  BakeSettings bake;  // [bake] as load_fabric_description parses it; resolution = the maps' side
  bool image_maps = false;  // [maps] (image files) rather than [weave]
};

// The bake settings of the description at `toml_path` without generating or decoding any map (a
// WIF draft: the defaults at options.resolution or kDefaultWeaveResolution):
// the TOML is read and parsed (at most 64 MiB, regular files only), [bake] is range-checked as
// load_fabric_description does, and the resolution is [bake] resolution (or options.resolution)
// for a weave, the height image's side from its header for an image fabric (no pixel read).
// Returns nullopt when the description cannot be read or has an error: the full load then reports
// it with its usual message. Warns nothing. Safe on untrusted input.
std::optional<FabricSettingsPeek> peek_fabric_settings(const std::string& toml_path,
                                                       const LoadOptions& options = {});

// load_fabric_description(toml_path).fabric.
Fabric load_fabric(const std::string& toml_path);

// A fabric from a named weave ("twill2/1", see weave::named_weave) with default yarn geometry,
// materials, sheen and bake settings, maps generated at `resolution` (pattern --weave).
LoadedFabric fabric_from_named_weave(const std::string& weave_name, int resolution);

// A fabric from a WIF draft (its colours, spacings and thicknesses), defaults otherwise, maps
// generated at `resolution` (pattern --wif). Fabric::inputs holds the WIF file and its hash.
LoadedFabric fabric_from_wif(const std::string& wif_path, int resolution);

// Valid range of map and bake resolutions.
inline constexpr int kMinResolution = 4;
inline constexpr int kMaxResolution = 8192;  // == inputs::kMaxMapSide

}  // namespace clothbake

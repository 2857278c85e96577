// The in-memory fabric: per-texel feature maps of one N x N tile plus model parameters and bake
// settings. Every bake stage reads a Fabric; nothing downstream reads files or TOML.
//
// Conventions (docs/architecture.md, docs/fabric-format.md):
//  - texel (x, y), row-major index y * N + x, u = (x + 0.5) / N in [0, 1)^2; row 0 is v = 0
//    (the top row of an image file);
//  - heights are in tile-side units (a height of 1 equals the width of the tile); converted from
//    the fabric file's physical units at load time;
//  - vectors are in the local shading frame of the macro surface: +z = macro normal, +x = u
//    (warp/weft directions: warp yarns run along y, weft yarns along x).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace clothbake {

using Vec3f = std::array<float, 3>;
using Rgb = std::array<double, 3>;

// Per-texel feature maps of one square, tileable tile. All vectors have resolution * resolution
// entries (row-major) once validated.
struct FabricMaps {
  int resolution = 0;             // N
  std::vector<float> height;      // tile-side units; >= 0 not required
  std::vector<Vec3f> tangent;     // unit fibre tangent (local frame)
  std::vector<Vec3f> normal;      // unit shading normal (local frame), z > 0
  std::vector<float> gap;         // I(x) in [0, 1]: 1 = yarn, 0 = gap (delta transmission)
  std::vector<uint16_t> yarn_id;  // index into FabricParams::yarns
  std::vector<Vec3f> albedo;      // linear RGB base colour of the yarn at this texel, [0, 1]

  std::size_t texel_count() const { return std::size_t(resolution) * std::size_t(resolution); }
  // Sets the resolution to n and every map to n^2 value-initialised texels (may throw bad_alloc).
  void allocate(int n) {
    resolution = n;
    const std::size_t count = texel_count();
    height.assign(count, 0.f);
    tangent.assign(count, Vec3f{});
    normal.assign(count, Vec3f{});
    gap.assign(count, 0.f);
    yarn_id.assign(count, 0);
    albedo.assign(count, Vec3f{});
  }
  std::size_t index(int x, int y) const {
    return std::size_t(y) * std::size_t(resolution) + std::size_t(x);
  }
};

// Optical parameters of one yarn material (paper Sec. 3; defaults in docs/fabric-format.md).
struct YarnMaterial {
  std::string name;                // "warp", "weft", or a WIF colour name
  double roughness = 0.3;          // SGGX fibre roughness sigma, (0, 1]
  double optical_thickness = 2.0;  // SpongeCake slab optical thickness T, > 0
  // Defaults sum to exactly 1 per channel (energy conservation, model::energy_excess = 0): the
  // earlier 0.8 / 0.3 / 0.2 scaled by 1 / 1.3 and rounded (docs/fabric-format.md).
  Rgb specular_albedo{0.6, 0.6, 0.6};  // single-scattering albedo alpha of the specular lobes
  Rgb diffuse_reflectance{0.25, 0.25, 0.25};  // higher-order scattering, reflection
  Rgb diffuse_transmittance{0.15, 0.15, 0.15};
  Rgb color{1.0, 1.0, 1.0};  // yarn colour (multiplies the albedos; the albedo map)
};

struct SheenParams {
  Rgb color{0.0, 0.0, 0.0};  // sheen albedo scale; zero disables sheen
  double roughness = 0.5;    // sheen roughness in (0, 1]
};

// Settings of the bake (defaults follow the paper, Sec. 3.2, 4.2-4.4, 6).
struct BakeSettings {
  int resolution = 256;              // texels per tile side of the baked maps
  int parallax_dirs = 32;            // parallax table: dirs x dirs view directions
  double parallax_min_cos = 0.6;     // parallax cap: directions with cos(theta) > this
  double parallax_max_error = 0.05;  // compressed parallax: RMS Eq. 2 offset error, texels
                                     // (= compress::kDefaultParallaxMaxError)
  int visibility_dirs = 20;          // visibility sampling: dirs x dirs light directions
  int radiance_dirs = 32;            // Integral-Radiance half-vector bins: dirs x dirs (the loader
                           // picks it from the narrowest roughness when the file does not)
  int clusters = 8;              // N_c visibility clusters (K-means)
  bool clusters_by_yarn = true;  // split every K-means cluster by yarn (no cluster mixes yarns)
  int visibility_rank = 4;       // per-cluster principal components of the visibility stored
                                 // for the multi-scale control variate (0: the cluster means)
  bool compress = true;          // C-PCA compress the Integral-Radiance tables
  int compress_clusters = 0;     // C-PCA clusters k per visibility cluster; 0: auto (1)
  int compress_rank = 0;         // C-PCA rank r (fixed shape); 0: auto (ranks for a target error)
  uint64_t seed = 1;             // seed of every randomised step (k-means++, verify sampling)
};

// One input file the fabric was built from, with its content hash (provenance in the asset).
struct InputFile {
  std::string role;  // "fabric", "height", "tangent", "wif", ...
  std::string path;
  std::string xxh64;  // 16 hex digits of XXH64(content, seed 0)
};

struct Fabric {
  std::string name;
  FabricMaps maps;
  std::vector<YarnMaterial> yarns;  // indexed by FabricMaps::yarn_id
  SheenParams sheen;
  BakeSettings bake;
  std::vector<InputFile> inputs;
  // Physical width of the tile (along u) in millimetres, the unit that heights were converted
  // from; 0 when the description gives no physical size ([tile] units = "tile").
  double tile_size_mm = 0.0;
};

}  // namespace clothbake

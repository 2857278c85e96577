// Small deterministic fabrics for tests (formats, pipeline). Every value is a short binary
// fraction or an exact ratio so that the bytes do not depend on the platform's libm.
#pragma once

#include <cstdint>
#include <string>

#include "fabric/fabric.hpp"

namespace clothbake::test_support {

// A plain weave of two yarns on an n x n tile: warp (yarn 0, tangent +y) on texels where
// (x / 2 + y / 2) is even, weft (yarn 1, tangent +x) elsewhere; a one-texel gap every 4 texels.
inline Fabric make_test_fabric(int n, const std::string& name = "test-plain") {
  Fabric f;
  f.name = name;
  f.maps.allocate(n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const std::size_t i = f.maps.index(x, y);
      const bool warp = ((x / 2 + y / 2) % 2) == 0;
      f.maps.height[i] = float((x * 3 + y * 5) % 7) / 64.f;
      f.maps.tangent[i] = warp ? Vec3f{0.f, 1.f, 0.f} : Vec3f{1.f, 0.f, 0.f};
      f.maps.normal[i] = warp ? Vec3f{0.6f, 0.f, 0.8f} : Vec3f{0.f, -0.6f, 0.8f};
      f.maps.gap[i] = (x % 4 == 3 && y % 4 == 3) ? 0.f : 1.f;
      f.maps.yarn_id[i] = warp ? 0 : 1;
      f.maps.albedo[i] = warp ? Vec3f{0.75f, 0.5f, 0.25f} : Vec3f{0.125f, 0.25f, 0.5f};
    }
  YarnMaterial warp_yarn;
  warp_yarn.name = "warp";
  warp_yarn.roughness = 0.25;
  warp_yarn.color = {0.75, 0.5, 0.25};
  YarnMaterial weft_yarn;
  weft_yarn.name = "weft";
  weft_yarn.roughness = 0.5;
  weft_yarn.optical_thickness = 4.0;
  weft_yarn.color = {0.125, 0.25, 0.5};
  f.yarns = {warp_yarn, weft_yarn};
  f.sheen.color = {0.25, 0.25, 0.25};
  f.sheen.roughness = 0.5;
  f.bake.resolution = n;
  f.tile_size_mm = 2.5;
  f.inputs.push_back({"fabric", name + ".toml", "0123456789abcdef"});
  return f;
}

}  // namespace clothbake::test_support

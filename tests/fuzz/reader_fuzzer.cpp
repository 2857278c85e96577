// libFuzzer harness for the reader library: any byte string must open cleanly or fail with a
// Status; everything reachable from an opened asset (typed views, fabric sections, validation)
// must stay in bounds. Built with -fsanitize=fuzzer,address,undefined (tests/fuzz/CMakeLists.txt).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/validate/validate.hpp"

using namespace clothbake::reader;

// Touches a float without converting it (a float-to-integer conversion of garbage is UB).
static uint64_t bits(float value) {
  uint32_t b;
  std::memcpy(&b, &value, 4);
  return b;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // An exact-size copy (so AddressSanitizer sees any read past `size`); operator new[] returns
  // memory aligned for any fundamental type, which satisfies the reader's 8-byte requirement.
  std::unique_ptr<unsigned char[]> copy(new unsigned char[size ? size : 1]);
  if (reinterpret_cast<uintptr_t>(copy.get()) % 8 != 0) __builtin_trap();
  if (size) std::memcpy(copy.get(), data, size);
  const unsigned char* words = copy.get();
  // Once as opened (structure only), once only if every checksum holds.
  for (bool checksums : {false, true}) {
    Asset asset;
    if (!asset.open_memory(words, size).ok()) continue;
    if (checksums && !verify_checksums(asset).ok()) continue;
    volatile uint64_t sink = 0;
    for (uint32_t i = 0; i < asset.section_count(); ++i) {
      SectionInfo info;
      if (!asset.section(i, &info).ok()) __builtin_trap();
      for (uint64_t b = 0; b < info.stored_size; b += 61)
        sink = sink + info.data[b];
      if (info.stored_size) sink = sink + info.data[info.stored_size - 1];
      (void)verify_section(asset, info);
      ArrayView<float> floats;
      if (asset.view_of(info, &floats).ok() && floats.size)
        sink = sink + bits(floats[floats.size - 1]);
    }
    FeatureMaps maps;
    if (read_feature_maps(asset, &maps).ok()) {
      const uint64_t texels = uint64_t(maps.resolution) * maps.resolution;
      if (texels) {
        // Every decoded map's last element (format 1.4 maps are decoded into owned storage).
        sink = sink + bits(maps.height[texels - 1]) + maps.yarn_id[texels - 1] +
               bits(maps.albedo[3 * texels - 1]) + bits(maps.normal[3 * texels - 1]) +
               bits(maps.tangent[3 * texels - 1]) + bits(maps.gap[texels - 1]);
      }
    }
    const FabricInfoRecord* info;
    if (read_fabric_info(asset, &info).ok()) sink = sink + info->yarn_count;
    ArrayView<YarnMaterialRecord> yarns;
    if (read_yarn_materials(asset, &yarns).ok())
      for (const auto& y : yarns)
        sink = sink + uint64_t(y.name[0]);
    std::string_view json;
    if (asset.metadata_json(&json).ok() && !json.empty()) sink = sink + uint64_t(json.back());
    for (ParallaxSource source : {ParallaxSource::Raw, ParallaxSource::Compressed}) {
      ParallaxView parallax;  // both forms: per-texel and footprint queries at the tile's edges
      if (!parallax.open(asset, source).ok()) continue;
      const double n = parallax.resolution(), view[3] = {0.3, -0.7, 0.5};
      ParallaxSample sample;
      (void)parallax.depth(-1, int64_t(n), view, &sample);
      (void)parallax.decode_all();  // the entropy-coded form: every block
      if (parallax.has_sat())
        (void)parallax.footprint_depth({-0.5, n - 0.25, n + 1.5, 2 * n}, view, &sample);
      sink = sink + uint64_t(sample.r < 0);
    }
    validate_asset(asset, nullptr, nullptr);
  }
  return 0;
}

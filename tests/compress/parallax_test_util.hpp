// What the tests of the entropy-coded and the hierarchical parallax forms share: finding one of
// their sections to edit, and checking that an edited (hostile) asset is refused with stable IDs.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/status.hpp"
#include "raycast/parallax.hpp"
#include "tests/raycast/synthetic_fields.hpp"
#include "tests/support/memory_asset.hpp"

namespace clothbake::compress::test {

// The parallax table of `maps` ray cast at dirs x dirs view directions.
inline raycast::ParallaxTable baked(const FabricMaps& maps, int dirs = 8) {
  raycast::ParallaxSettings settings;
  settings.dirs = dirs;
  return raycast::bake_parallax(maps, settings);
}

// 16^2 texels of thin spikes 0.5 tile tall, 4 per tile side, on a flat floor: the field whose
// depths jump the most between neighbouring texels.
inline FabricMaps spiky_maps() {
  return raycast::rctest::maps_from(16, [](double x, double y) {
    return (std::fmod(x * 4, 1) < 0.1 && std::fmod(y * 4, 1) < 0.1) ? 0.5 : 0.0;
  });
}

// The ParallaxEntropy section of `instance` in `sections` (both forms store theirs under that
// type); throws std::runtime_error when there is none.
inline formats::Section& parallax_entropy_section(std::vector<formats::Section>& sections,
                                                  uint32_t instance) {
  for (auto& s : sections)
    if (s.type == reader::SectionType::ParallaxEntropy && s.instance == instance) return s;
  throw std::runtime_error("no such section");
}

// `sections` written as an asset: ParallaxView::open fails with `open_id` (or "" when it opens),
// validation reports `validate_id`, and when the view opens its queries stay in bounds and answer.
inline void expect_hostile_parallax(const std::vector<formats::Section>& sections,
                                    const char* open_id, const char* validate_id) {
  test_support::MemoryAsset m(sections);
  ASSERT_TRUE(m.status.ok()) << m.status.message();
  reader::ParallaxView view;
  const reader::Status st = view.open(m.asset);
  EXPECT_EQ(std::string(reader::check_id(st.check())), open_id) << st.message();
  const std::string ids = test_support::validate_ids(m.asset);
  EXPECT_NE(ids.find(validate_id), std::string::npos) << ids;
  if (st.ok()) {
    const double v[3] = {0.3, 0.2, 0.9};
    reader::ParallaxSample out;
    EXPECT_TRUE(view.depth(1, 2, v, &out).ok());
    EXPECT_TRUE(view.footprint_depth({0, 0, 5, 5}, v, &out).ok());
  }
}

}  // namespace clothbake::compress::test

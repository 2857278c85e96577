// The block coder (compress/parallax_entropy.hpp encodes, formats/reader/parallax_entropy.hpp
// decodes; the feature maps code each byte plane with it): a block decodes to exactly its plane,
// the tile's repeat shift makes a repeating plane smaller, and every single-byte corruption and
// truncation of a block is reported (CBK-E021) without reading out of bounds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "compress/parallax_entropy.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "raycast/parallax.hpp"
#include "tests/compress/corrupt_blocks.hpp"
#include "tests/compress/parallax_test_util.hpp"
#include "tests/raycast/synthetic_fields.hpp"

using namespace clothbake;
using namespace clothbake::raycast;

namespace {

using compress::test::baked;

// The low bytes of direction d's depth codes: a byte plane with the structure (and the period) of
// a woven tile.
std::vector<uint8_t> byte_plane(const ParallaxTable& table, int d) {
  const uint64_t plane = uint64_t(table.resolution) * table.resolution;
  std::vector<uint8_t> out(plane);
  for (uint64_t t = 0; t < plane; ++t)
    out[t] = uint8_t(table.depth[uint64_t(d) * plane + t]);
  return out;
}

}  // namespace

TEST(BlockCoder, UsesTheTilesRepeat) {
  // A plain weave of 4 threads on 32^2 repeats after (16, 16) (and (16, 0), (0, 16)).
  const uint32_t n = 32;
  const std::vector<uint8_t> plane = byte_plane(baked(rctest::plain_weave_maps(32, 4), 4), 10);
  const auto candidates = compress::parallax_shift_candidates(plane.data(), n);
  ASSERT_FALSE(candidates.empty());
  const auto [sx, sy] = candidates[0];
  // Without the shift the same plane costs more, and both decode exactly.
  const std::vector<uint16_t> f0 =
      compress::parallax_frequencies(compress::parallax_residual_counts(plane.data(), n, 0, 0));
  const std::vector<uint16_t> f1 =
      compress::parallax_frequencies(compress::parallax_residual_counts(plane.data(), n, sx, sy));
  const std::vector<uint8_t> plain =
      compress::encode_parallax_block(plane.data(), n, 0, 0, 0, f0.data());
  const std::vector<uint8_t> shifted =
      compress::encode_parallax_block(plane.data(), n, sx, sy, 0, f1.data());
  EXPECT_LT(shifted.size(), plain.size());
  reader::ParallaxEntropyScratch scratch;
  std::vector<uint8_t> decoded(n * n);
  ASSERT_TRUE(reader::decode_parallax_block(shifted.data(), shifted.size(), f1.data(), 1, n,
                                            decoded.data(), &scratch)
                  .ok());
  EXPECT_EQ(decoded, plane);
}

TEST(BlockCoder, EveryCorruptionOrTruncationOfABlockIsSafe) {
  const uint32_t n = 16;
  const std::vector<uint8_t> codes = byte_plane(baked(rctest::plain_weave_maps(16), 2), 0);
  const std::vector<uint16_t> f =
      compress::parallax_frequencies(compress::parallax_residual_counts(codes.data(), n, 0, 0));
  const std::vector<uint8_t> block =
      compress::encode_parallax_block(codes.data(), n, 0, 0, 0, f.data());
  reader::ParallaxEntropyScratch scratch;
  std::vector<uint8_t> plane(n * n);
  ASSERT_TRUE(reader::decode_parallax_block(block.data(), block.size(), f.data(), 1, n,
                                            plane.data(), &scratch)
                  .ok());
  EXPECT_TRUE(std::equal(plane.begin(), plane.end(), codes.begin()));
  compress_test::expect_corruptions_detected(
      block,
      [&](const std::vector<uint8_t>& b) {
        return reader::decode_parallax_block(b.data(), b.size(), f.data(), 1, n, plane.data(),
                                             &scratch);
      },
      [](std::size_t) {});
  // A group beyond the tables, a shift outside the tile.
  std::vector<uint8_t> bad = block;
  bad[4] = 1;
  EXPECT_FALSE(
      reader::decode_parallax_block(bad.data(), bad.size(), f.data(), 1, n, plane.data(), &scratch)
          .ok());
  bad = block;
  bad[0] = 16;
  EXPECT_FALSE(
      reader::decode_parallax_block(bad.data(), bad.size(), f.data(), 1, n, plane.data(), &scratch)
          .ok());
}

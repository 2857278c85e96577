// Every one-bit flip (bits 0 and 7 of each byte) and every truncation of a coded parallax block,
// decoded by the caller's decoder: flips fail with CBK-E021 or decode harmlessly, and the
// final-state check catches at least 90 % of them; every truncation fails with CBK-E021. Each
// corrupted copy is its exact size, so ASan sees any read past it. `after_cut(len)` runs after each
// truncated decode (for checks of the decoder's output).
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "formats/reader/status.hpp"

namespace clothbake::compress_test {

template <class Decode, class AfterCut>
void expect_corruptions_detected(const std::vector<uint8_t>& block, Decode decode,
                                 AfterCut after_cut) {
  int detected = 0, total = 0;
  for (std::size_t i = 0; i < block.size(); ++i)
    for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80)}) {
      std::vector<uint8_t> bad = block;
      bad[i] ^= flip;
      const reader::Status s = decode(bad);
      ++total;
      if (!s.ok()) {
        ++detected;
        EXPECT_EQ(std::string(reader::check_id(s.check())), "CBK-E021");
      }
    }
  EXPECT_GE(detected, total * 9 / 10) << "the final-state check catches almost every flip";
  for (std::size_t len = 0; len < block.size(); ++len) {
    const std::vector<uint8_t> cut(block.begin(), block.begin() + std::ptrdiff_t(len));
    const reader::Status s = decode(cut);
    EXPECT_FALSE(s.ok()) << len;
    EXPECT_EQ(std::string(reader::check_id(s.check())), "CBK-E021");
    after_cut(len);
  }
}

}  // namespace clothbake::compress_test

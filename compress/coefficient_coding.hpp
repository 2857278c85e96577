// Encoder of the entropy-coded C-PCA coefficients (part 5 of radiance_compressed; the prediction,
// the stream and the decoder:
// formats/reader/compressed_coefficients.hpp; why and what it measured: docs/compression.md,
// "Coded coefficients").
//
// Lossless: the decoded coefficients are exactly the set's. The encoder tries no shift and up to
// three of the tile's repeats (parallax_shift_candidates on a fingerprint of each texel's cell and
// coefficients, shifts shorter than max(4, N / 16) left out) and keeps the smallest stream.
// Deterministic, single-threaded, C++20.
// Errors: Error(Internal) for an inconsistent set.
#pragma once

#include <cstdint>
#include <vector>

#include "compress/compressed_set.hpp"

namespace clothbake::compress {

// The part 5 stream of `set`'s coefficients with shift (sx, sy) ((0, 0): none).
std::vector<uint8_t> encode_compressed_coefficients(const CompressedTableSet& set, uint32_t sx,
                                                    uint32_t sy);

// The smallest stream over no shift and the cell map's repeats.
std::vector<uint8_t> code_compressed_coefficients(const CompressedTableSet& set);

}  // namespace clothbake::compress

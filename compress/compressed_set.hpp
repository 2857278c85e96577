// Compression of one table kind into the sections of formats/reader/compressed_layout.hpp:
// C-PCA (compress/cpca.hpp) of the per-texel directional vectors, then quantisation.
//
// Quantisation (docs/compression.md has the measurements):
//  - every image's directional vector (a cell mean or a basis vector) is divided by its largest
//    magnitude and stored as IEEE binary16: values in [-1, 1] keep 11 significant bits;
//  - coefficients are stored as int16 per (cell, component) with step max|c| / 32767 (symmetric,
//    -32768 never used), the step folded into the image's f32 scale;
//  - the cell map is u8, the cells u32.
// Zero-valued texels (all bins) get no cell and no coefficients.
//
// Determinism: same data and options, same bytes, whatever the thread count.
// C++20. Errors: clothbake::Error(Input) for options out of range or data that cannot be stored
// (more than 254 cells or 4096 images: lower k or r), NaN/Inf/negative values (naming the texel).
#pragma once

#include <cstdint>
#include <vector>

#include "compress/cpca.hpp"
#include "compress/directional_texels.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/compressed_layout.hpp"

namespace clothbake::formats {
struct Section;
}

namespace clothbake::compress {

// Exactly the six sections of one kind.
struct CompressedTableSet {
  reader::CompressedTableInfoRecord info{};
  std::vector<reader::CompressedCell> cells;
  std::vector<uint8_t> cell_map;      // N x N
  std::vector<float> scales;          // images
  std::vector<reader::Half> basis;    // images x bins
  std::vector<int16_t> coefficients;  // per texel in row-major order, its cell's rank
  // Part 5 as stored: the coefficients entropy-coded (coefficient_coding.hpp); compress_tables
  // fills it, compressed_sections codes the coefficients when it is empty.
  std::vector<uint8_t> coded_coefficients;
  // A scene-planned kind (info.flags kCompressedPlannedFlag): one entry per bin, 1 = covered
  // (bin_map instance 0). Part 4 then stores the covered bins' columns only, in bin order
  // (docs/format.md §6.13); `basis` above keeps every bin (zero where not covered).
  std::vector<uint8_t> covered;

  bool empty() const { return cells.empty(); }
  // Columns of part 4 as stored: the covered bins of a planned kind, else every bin.
  uint64_t stored_columns() const;
  // Bytes of the six payloads as stored (part 5: coded_coefficients, coded now if empty).
  uint64_t payload_bytes() const;
};

struct CompressionStats {
  double cpca_error = 0.0;     // relative RMS texel error of the C-PCA (before quantisation)
  double error = 0.0;          // relative RMS texel error of the stored tables (after quantisation)
  double max_abs_error = 0.0;  // largest |decompressed - raw| texel value
  double max_value = 0.0;      // largest raw texel value
  int cells = 0, images = 0, total_rank = 0, min_rank = 0, max_rank = 0;
  int iterations = 0;
  uint64_t stored_clusters = 0;   // visibility clusters with a non-zero texel
  uint64_t raw_float_bytes = 0;   // stored clusters x bins x N^2 x 4: the float SATs
  uint64_t compressed_bytes = 0;  // payload_bytes()
  double ratio() const { return compressed_bytes ? double(raw_float_bytes) / compressed_bytes : 0; }
};

// Compresses `data` (checked with check_finite_non_negative first).
CompressedTableSet compress_tables(const DirectionalTexels& data, const CpcaOptions& options,
                                   CompressionStats* stats = nullptr);

// The six sections (none for an empty set), part 5 the entropy-coded coefficients
// (coefficient_coding.hpp); set.info.flags as set (kCompressedPlannedFlag for a planned kind).
// Throws Error(Internal) for an inconsistent set.
std::vector<formats::Section> compressed_sections(const CompressedTableSet& set);

// Decompressed texel values of a set with the reader's arithmetic (scale * half basis * weight),
// for tests and the report: out gets texels x bins floats (0 for texels without a cell).
std::vector<float> decompress_texels(const CompressedTableSet& set);

}  // namespace clothbake::compress

// Encoder of the compressed parallax (the hierarchical form, sections parallax_entropy; the
// prediction, the block format and the decoder: formats/reader/parallax_hierarchy.hpp; why
// and what it measured: docs/compression.md, "Hierarchical parallax").
//
// Quantisation. Each direction d gets its own step from the error target: a uniform quantiser of
// step s has an RMS depth error s / sqrt(12), and a depth error moves the Eq. 2 offset by
// N tan(theta_d) times it, so
//   step[d] = sqrt(12) * max_error / T_d,   T_d = max of N tan(theta) over d and its 4 grid
//                                            neighbours (the bin centres)
// gives every direction the same share of the target (the allocation that minimises the coded
// size for a given mean squared error at these rates), and taking T over the neighbours keeps the
// bilinear lookup between a direction near the pole (tiny T, coarse step) and the next ring within
// the target too. Steps are at least range / 65535 (codes fit 16 bits) and at most the range (a
// coarser step only sets every code to 0 or 1), then rounded to integer multiples m[d] of one unit
// (min step / 1024, at least max step / 2^24) so that directions predict each other exactly in
// integers. The codes round the raw depths: c = round(raw code * depth_scale / step[d]). The RMS
// offset error against the raw table is measured at every texel and bin centre, and the steps are
// rescaled by the ratio of the target to it (up or down, at most six rounds, stopping within 1 %)
// so that the table uses the whole budget without exceeding it; the rounds' largest steps within
// the target are kept. (Only a target below what the finest steps reach is missed: the caller
// warns.)
//
// Coding. Every block is predicted from its references (parallax_hierarchy.hpp) and coded with the
// block coder's rANS (compress/parallax_entropy.hpp); each block tries no shift and the table's
// translational self-similarities (parallax_shift_candidates on the middle direction's codes) and
// keeps the one with the smallest estimated size. Blocks share frequency tables by group: all in
// one group, one group per level, or one per level and ring of the direction grid
// (hierarchical_group), whichever gives the smallest estimated total with the tables' 11 776 bytes
// each.
//
// Deterministic: blocks are measured and coded in parallel (TBB), but each block's bytes depend
// only on its codes and its references', and the tables are summed in block order. C++20. Errors:
// Error(Input) for an empty table or max_error outside (0, 1] (naming bake.parallax_max_error).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "compress/parallax_codes.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::compress {

struct HierarchicalParallax {
  int resolution = 0, dirs = 0;
  double min_cos = 0.6, reference_height = 0.0, max_offset = 0.0;
  std::vector<double> steps;      // D: tile-side units per code
  std::vector<uint32_t> weights;  // D: m[d], steps[d] = unit * m[d]
  std::vector<uint16_t> codes;    // D x N x N
  // Against the raw codes, at every texel and bin centre.
  double rms_offset_error = 0.0;     // texels
  double max_offset_error = 0.0;     // texels
  double share_above_quarter = 0.0;  // share of entries with offset error > 0.25 texel
  double max_depth_error = 0.0;      // tile-side units
  int quantisation_rounds = 0;       // how often the steps were made (1 unless shrunk)
  bool planned = false;              // only the kept directions are stored (kEntropyPlannedFlag)
  uint32_t max_code = 0;
  // The coded form.
  std::vector<uint64_t> offsets;  // D + 1 block offsets into stream
  std::vector<uint8_t> stream;
  std::vector<uint16_t> tables;  // groups x kHierContexts x 256
  uint32_t groups = 0;
  std::vector<std::pair<uint32_t, uint32_t>> candidates;
  uint32_t shifted_blocks = 0;
  double seconds_quantise = 0.0, seconds_code = 0.0;

  uint64_t payload_bytes() const {
    return 64 + steps.size() * 12 + offsets.size() * 8 + stream.size() + tables.size() * 2;
  }
};

// Quantises the raw table for max_error (RMS Eq. 2 offset error in texels) and codes it (header
// comment). With `keep` (one entry per direction, a scene plan's view bins; empty: all) only the
// kept directions are coded and measured; the others get empty blocks, and the sections are
// flagged planned (coverage: bin_map instance 1). The kept set must contain every direction a
// kept one references (reader::close_under_parallax_references; Error(Internal) otherwise); the
// kept directions' codes are those of the full bake. Throws Error(Input) as documented there.
HierarchicalParallax hierarchical_parallax(const ParallaxCodes& raw,
                                           double max_error = kDefaultParallaxMaxError,
                                           const std::vector<uint8_t>& keep = {});

// Directions a plan's keep mask keeps (its non-zero entries; one entry per view bin).
std::size_t kept_direction_count(const std::vector<uint8_t>& keep);

// The finest grouping of bin (i, j) of an n x n grid: 4 * level + ring quarter (0-11).
uint32_t hierarchical_group(uint32_t i, uint32_t j, uint32_t n);

// Encodes direction d's codes as one block (exposed for tests): `codes` is the whole D x N x N
// table (the references are read from it), `freq` the group's tables.
std::vector<uint8_t> encode_hierarchical_block(const HierarchicalParallax& p, uint32_t d,
                                               uint32_t sx, uint32_t sy, uint32_t group,
                                               const uint16_t* freq);

// parallax_entropy instances 0 (info: bits 16, flags 0 or kEntropyPlannedFlag), 1 (steps),
// 2 (offsets), 3 (stream), 4 (tables {G, 23, 256}) and 5 (weights), all of payload version 1.
std::vector<formats::Section> hierarchical_parallax_sections(const HierarchicalParallax& p);

}  // namespace clothbake::compress

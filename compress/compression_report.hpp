// The sweep behind `clothbake report compression` (docs/compression.md, "Report"): compresses one
// kind's tables with many settings and measures, for each, the stored size, the error of square
// footprints of every size (1, 2, 4, 8, 16, 64 texels per side, one tile, three tiles) and the
// decode time, so that size can be plotted against error and error against run time.
//
// Rows:
//  - layout "texel" (what clothbake stores, compressed_set.hpp): fixed (k, r) shapes and target
//    errors; queries through the reader (formats/reader/compressed_tables.hpp);
//  - layout "sat" (the paper's, sat_pca.hpp) with normalisation none / plane / plane+unit, at a
//    reduced resolution (it fits C x B x N^2 floats), with the texel layout at that resolution
//    for an apples-to-apples comparison; queries through the unoptimised in-memory model;
//  - layout "raw": the raw fixed-point tables (optional; built in memory), the reference size and
//    query time.
// Footprint error: sqrt(sum (F - F_ref)^2 / sum F_ref^2) over random positions, half vectors and
// every cluster, F_ref the direct sum of the uncompressed texel values. Times: thread CPU time on
// one thread (not disturbed by other processes), compression on all threads (process CPU time
// and wall time).
//
// C++20. Errors: as compress_tables / SatPcaModel::fit.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "compress/directional_texels.hpp"

namespace clothbake::compress {

struct ReportOptions {
  std::vector<int> clusters = {1, 2, 4};       // texel layout: k per visibility cluster
  std::vector<int> ranks = {2, 4, 8, 16, 32};  // texel layout: fixed r
  std::vector<double> targets = {0.03, 0.02, 0.01, 0.008, 0.005};  // texel layout, k = 1
  std::vector<std::pair<int, int>> sat_shapes = {{4, 10}, {1, 10}, {4, 20}, {1, 40}, {8, 10}};
  bool sat = true;    // run the paper's layout (needs `low` data)
  bool raw = true;    // measure the raw tables (needs the fill inputs: see RawTablesBuilder)
  int samples = 300;  // footprints per size class
  int timing_queries = 20000;
  uint64_t seed = 1;
};

// Square footprint sides measured (texels); the last two are 1 and 3 tiles of the data's N.
std::vector<double> report_sides(int resolution);

struct ReportRow {
  std::string layout;               // "texel", "sat", "raw"
  std::string normalisation = "-";  // sat: none / plane / plane+unit; "-" otherwise
  std::string mode = "-";           // "fixed" or "target" ("-" for raw)
  int resolution = 0;
  int clusters = 0;     // k (per visibility cluster for "texel", total for "sat")
  int rank = 0;         // r (fixed) or largest rank chosen (target)
  double target = 0.0;  // target error (texel, target mode)
  int images = 0;       // texel: images; sat: groups x (1 + r)
  uint64_t stored_bytes = 0;
  uint64_t raw_float_bytes = 0;
  double ratio = 0.0;
  uint64_t decoded_bytes = 0;           // memory the reader holds (texel, raw)
  double texel_error = 0.0;             // relative RMS texel error (texel layout)
  double normalised_mse = 0.0;          // the paper's MSE of normalised SATs (sat layout)
  std::vector<double> footprint_error;  // per report_sides()
  double query_ns = 0.0;                // per query of all clusters, one thread
  double compress_cpu_seconds = 0.0, compress_wall_seconds = 0.0;
  bool paper_point = false;  // sat plane+unit k=4 r=10
};

// Builds the raw fixed-point tables of `data`'s kind in memory and returns an opened asset buffer
// (for the "raw" row); supplied by the caller, which has the fill inputs.
using RawTablesBuilder = std::function<std::vector<std::byte>()>;

// Runs the sweep on `full` (and the sat rows on `low`, the same fabric at a lower resolution, when
// options.sat and low != nullptr). progress(done, total, label) is called before each row.
std::vector<ReportRow> compression_sweep(
    const DirectionalTexels& full, const DirectionalTexels* low, const ReportOptions& options,
    const RawTablesBuilder& raw_builder = {},
    const std::function<void(int, int, const std::string&)>& progress = {});

// CSV: a header line, then one line per row (sides as columns "fp_<side>").
std::string report_csv(const std::vector<ReportRow>& rows, const std::vector<double>& sides);

}  // namespace clothbake::compress

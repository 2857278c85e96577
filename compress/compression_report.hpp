// The sweep behind `clothbake report compression` (docs/compression.md, "Report"): compresses one
// kind's tables with many settings and measures, for each, the stored size, the error of square
// footprints of every size (1, 2, 4, 8, 16, 64 texels per side, one tile, three tiles) and the
// decode time, so that size can be plotted against error and error against run time.
//
// Rows:
//  - layout "texel" (what clothbake stores, compressed_set.hpp): fixed (k, r) shapes and target
//    errors; queries through the reader (formats/reader/compressed_tables.hpp);
//  - layout "raw": the raw fixed-point tables (optional; built in memory), the reference size and
//    query time.
// The paper's whole-SAT layout is not stored by clothbake and is measured outside the product, by
// benchmarks/compress/sat_layout_study.cpp: it writes "sat" rows (normalisation, normalised_mse,
// paper_point filled) with report_csv, measured by the same probes and helpers (report_probes,
// measure_queries, texel_row) as the sweep's rows.
// Footprint error: sqrt(sum (F - F_ref)^2 / sum F_ref^2) over random positions, half vectors and
// every cluster, F_ref the direct sum of the uncompressed texel values. Times: thread CPU time on
// one thread (not disturbed by other processes), compression on all threads (process CPU time
// and wall time).
//
// C++20. Errors: as compress_tables.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "compress/cpca.hpp"
#include "compress/directional_texels.hpp"
#include "formats/reader/radiance_query.hpp"

namespace clothbake::compress {

struct ReportOptions {
  std::vector<int> clusters = {1, 2, 4};       // texel layout: k per visibility cluster
  std::vector<int> ranks = {2, 4, 8, 16, 32};  // texel layout: fixed r
  std::vector<double> targets = {0.03, 0.02, 0.01, 0.008, 0.005};  // texel layout, k = 1
  bool raw = true;    // measure the raw tables (needs the fill inputs: see RawTablesBuilder)
  int samples = 300;  // footprints per size class
  int timing_queries = 20000;
  uint64_t seed = 1;
};

// Square footprint sides measured (texels); the last two are 1 and 3 tiles of the data's N.
std::vector<double> report_sides(int resolution);

struct ReportRow {
  std::string layout;               // "texel", "raw" (the study: "sat")
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

// Runs the sweep on `data`. progress(done, total, label) is called before each row.
std::vector<ReportRow> compression_sweep(
    const DirectionalTexels& data, const ReportOptions& options,
    const RawTablesBuilder& raw_builder = {},
    const std::function<void(int, int, const std::string&)>& progress = {});

// What the rows of one data set are measured on: `samples` random square footprints per size class
// of report_sides() (random positions and half vectors), and their reference F_c, the direct sums
// of the uncompressed texel values (probes x clusters).
struct ReportProbe {
  reader::Footprint rect;
  double h[3];
  std::size_t side = 0;  // index into report_sides
};
struct ReportProbes {
  std::vector<ReportProbe> probes;
  std::vector<double> reference;
};
ReportProbes report_probes(const DirectionalTexels& data, int samples, uint64_t seed);

// A layout's F_c of every cluster of `data` for one footprint and half vector; false on refusal.
using QueryAll = std::function<bool(const reader::Footprint&, const double*, double*)>;

// Fills row->footprint_error (per report_sides(); NaN when a query refuses) from `probes`, and
// row->query_ns from `timing_queries` random footprints (1 to 16 texels) on one thread.
void measure_queries(const DirectionalTexels& data, const ReportProbes& probes,
                     const QueryAll& query, int timing_queries, uint64_t seed, ReportRow* row);

// Runs `compress` and records its process CPU time and wall time in `row`.
void time_compression(const std::function<void()>& compress, ReportRow* row);

// Size of `data`'s tables as raw floats: stored clusters x bins x N^2 x 4 bytes.
uint64_t raw_float_bytes(const DirectionalTexels& data);

// One "texel" row: compresses `data` with `cpca`, opens the result through the reader, measures it
// on `probes` (options: timing_queries, seed).
ReportRow texel_row(const DirectionalTexels& data, const CpcaOptions& cpca,
                    const ReportProbes& probes, const ReportOptions& options);

// CSV: a header line, then one line per row (sides as columns "fp_<side>").
std::string report_csv(const std::vector<ReportRow>& rows, const std::vector<double>& sides);

}  // namespace clothbake::compress

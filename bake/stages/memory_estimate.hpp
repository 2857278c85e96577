// Up-front estimate of a bake's peak memory (docs/pipeline.md, "Memory estimate"), from the bake
// settings alone: no map decoded, nothing allocated in proportion to the settings. `clothbake
// bake` calls it before loading the maps and refuses (exit 2, naming the [bake] keys) a bake whose
// estimated peak exceeds --max-memory, instead of running until the allocator or the kernel ends
// it.
//
// Model: the driver keeps every artifact until the bake ends (the write stage reads every section),
// so a stage's peak is what the stages before it left resident plus its own working memory and
// outputs. Each stage's figure follows the allocations of its algorithm library (the sizes below
// are those of the code, per texel T = resolution^2, per direction D = parallax_dirs^2 or V =
// visibility_dirs^2, per half-vector bin B = radiance_dirs^2, per cluster K = clusters):
//   load_fabric   feature maps 46 T bytes (plus the decoded images of an image fabric, 48 T)
//   feature_maps  their sections, another 46 T
//   parallax      16-bit codes 2 D T, the compressed form (its codes, coded stream, sections)
//                 or the raw codes and SATs 6 D T, the height field's Embree BVH
//   visibility    samples T ceil(V / 64) 8, ASG records, decoded lobes and sections
//   cluster       K-means features and labels
//   tables        raw SATs B T K e (e = 4 or 8 bytes, tables/fixed_point_sat.hpp) plus the gap
//                 table T K e, or (compressed only) the streaming fills' copies of the inputs
//   compress      per-texel directional vectors 4 T B, the fill's per-thread blocks, the C-PCA's
//                 randomized SVD (Y, Q, QR, block partials of A^T Q) at its widest rank, the
//                 coefficients and the compressed set
//   write         the metadata section (sections are written from where the stages keep them)
// Upper bounds where the maps decide (every cluster stored, a gap table present, 16-bit parallax
// codes, one C-PCA stratum holding every texel), so the estimate is at or above the measured peak;
// one exception: the C-PCA's target mode is counted at its first rank cap (16), as the example
// fabrics need; a table that saturates it refits at 32 and 64, up to 3x the C-PCA's working
// memory (a small share of the directional vectors). Calibration in docs/performance.md.
//
// Pure and cheap (no allocation proportional to the settings); safe for any settings in the
// loader's ranges (sizes are computed in double, so nothing overflows).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "compress/compress_settings.hpp"
#include "fabric/fabric.hpp"

namespace clothbake::stages {

struct MemoryEstimateInput {
  BakeSettings bake;  // resolution = the maps' side (an image fabric's image size)
  compress::CompressSettings compression;  // the resolved settings of the compress stage
  // The stages that run (names, any order); empty: every stage of bake_stages().
  std::vector<std::string> stages;
  bool image_maps = false;  // maps decoded from image files (else generated from a weave)
  int threads = 1;          // worker threads (per-thread buffers)
};

struct StageMemory {
  std::string stage;
  double peak_bytes = 0;      // process peak while the stage runs (resident + working + outputs)
  double working_bytes = 0;   // what the stage itself adds at its peak
  double kept_bytes = 0;      // what of it stays resident after the stage (its outputs)
  double resident_bytes = 0;  // what stays resident after it (everything before included)
  std::string what;           // the dominant allocation, for messages ("the per-texel ...")
  std::vector<std::string> keys;  // the [bake] keys its size grows with
};

struct MemoryEstimate {
  std::vector<StageMemory> stages;  // in run order, only the stages that run
  double peak_bytes = 0;            // the largest stage peak
  std::size_t peak_stage = 0;       // index into stages
};

// Resident memory of the process before any stage (executable and shared libraries: OpenImageIO,
// Embree, TBB, ...): 126 MiB measured for a 16^2 bake (docs/performance.md, "Memory estimate").
inline constexpr double kBaseProcessBytes = 128.0 * 1024 * 1024;

MemoryEstimate estimate_bake_memory(const MemoryEstimateInput& input);

// {"peak_bytes", "peak_stage", "stages": [{"name", "peak_bytes", "working_bytes", "keys"}, ...]}
// for the bake report (integers, bytes).
nlohmann::json memory_estimate_json(const MemoryEstimate& estimate);

// "23.4 GiB", "512 MiB", "16 KiB", "100 B" (binary units, 3 significant digits).
std::string format_bytes(double bytes);

// Throws Error(Input) when estimate.peak_bytes > max_bytes, naming the responsible [bake] keys
// with their values (the peak stage's, and those of earlier stages whose outputs make up at least
// a quarter of the peak), the stage, the dominant allocation, both sizes and what to lower, e.g.
// "[bake] resolution = 256, radiance_dirs = 256, clusters = 64 need ~16.3 GiB in the compress
// stage (...); --max-memory is 23.4 GiB". `where` prefixes the message (the fabric file).
void check_memory_estimate(const MemoryEstimate& estimate, const BakeSettings& bake,
                           double max_bytes, const std::string& where);

// The check every bake makes before loading its maps (`clothbake bake`, the on-the-fly bakes of a
// scene's fabrics): the fabric's settings peeked from `fabric_path` (no map decoded), the stages
// `stages` picks (empty or an unknown name: every stage), `threads` workers (0: every core), the
// estimate checked against `max_memory` by check_memory_estimate (Error(Input), naming the file).
// Nullopt when the settings cannot be read: the load then reports the error. `resolution`:
// bake --resolution (kFabricResolutionArtifact), none for the fabric's own.
std::optional<MemoryEstimate> check_fabric_memory(const std::string& fabric_path,
                                                  const compress::CompressRequest& compression,
                                                  const std::vector<std::string>& stages,
                                                  int threads, uint64_t max_memory,
                                                  std::optional<int> resolution = std::nullopt);

}  // namespace clothbake::stages

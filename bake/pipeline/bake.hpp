// One bake: fabric description in, one asset out (atomically), plus a JSON report. The request
// seeds the artifacts every bake starts from ("fabric_path" or "fabric", "output", the seeds) and
// runs the given stages (stages::bake_stages() from bake/stages: load_fabric ... write); the
// write stage publishes the AssetSummary below as "asset".
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bake/pipeline/driver.hpp"
#include "fabric/fabric.hpp"
#include "formats/writer/atomic_file.hpp"

namespace clothbake::pipeline {

// Artifact "output": where the write stage puts the asset.
struct OutputRequest {
  std::string path;
  bool force = false;         // replace an existing file that is not an asset
  bool defer_commit = false;  // leave the asset at its temporary name (AssetSummary::pending)
};

// Artifact "asset": what the write stage wrote.
struct SectionSummary {
  std::string name;  // section type name, or "0x...." if unknown
  uint32_t type = 0;
  uint32_t instance = 0;
  std::string element;
  std::vector<uint32_t> dims;
  uint64_t offset = 0;
  uint64_t bytes = 0;
  std::string checksum;  // 16 hex digits
};
struct AssetSummary {
  std::string path;
  uint64_t size_bytes = 0;
  std::string content_hash;  // header checksum, 16 hex digits
  std::vector<SectionSummary> sections;
  // The file already held these exact bytes: it was left untouched, mtime included (restat).
  bool unchanged = false;
  // With BakeRequest::defer_commit and a changed asset: the complete asset at its temporary name,
  // renamed over `path` by pending->commit(); dropping the last reference removes it.
  std::shared_ptr<formats::TempFile> pending;
};

struct BakeRequest {
  std::string fabric_path;       // read by the load_fabric stage...
  std::optional<Fabric> fabric;  // ...unless the fabric is given (tests, library use)
  std::string output_path;
  bool force = false;
  // The asset is written but not renamed into place: the caller commits AssetSummary::pending
  // after its own outputs (report, depfile, stdout) have succeeded, so that a failing command
  // leaves no asset.
  bool defer_commit = false;
  std::vector<std::string> stages;  // --stages (empty: all)
  RunOptions run;
  // Optional artifacts available to every stage from the start, beside "fabric"/"fabric_path" and
  // "output": options that a command line gives to a stage of another folder (e.g. the compress
  // stage's "compress_options") without bake/pipeline knowing their types. A stage reads them by
  // listing their names in Stage::collects. Names must not collide with the seeded ones above
  // (Error(Internal)). A seed named like a stage's output replaces it: a stage whose outputs are
  // all seeded does not run (plan_stages), one whose outputs are partly seeded is an
  // Error(Internal) when it tries to produce the seeded one.
  Artifacts seeds;
};

struct BakeResult {
  RunResult run;
  AssetSummary asset;
};

// Checks the output path first (so a bad path fails before any work), then runs `stages`, which
// must include a stage producing "asset" (the write stage). Throws clothbake::Error: Input for bad
// inputs and unwritable outputs, Usage for unknown stage names, Internal for pipeline bugs. On any
// error nothing is written at the output path.
BakeResult bake(const BakeRequest& request, const std::vector<Stage>& stages);

// The --report / --json document: per-stage wall time, CPU time and peak memory, totals,
// thread count, and the asset's size, hash and section list.
nlohmann::json bake_report_json(const BakeRequest& request, const BakeResult& result);

// Hex formatting shared by the report and `clothbake info`.
std::string hex64(uint64_t value);

}  // namespace clothbake::pipeline

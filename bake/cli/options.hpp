// Option groups and value parsers shared by the clothbake subcommands, so that every command
// spells --json and ASSET the same way and parses "a,b,c" lists and directions with the same
// rules and messages. Parsers throw CLI::ValidationError naming the option (exit code 1).
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "eval/evaluator.hpp"

namespace clothbake::cli {

// --json: print the command's answer as one JSON document on stdout (print_json). `help` says
// what the document holds.
CLI::Option* add_json_flag(CLI::App& app, bool& json,
                           const std::string& help = "print one JSON document on stdout");

// ASSET: the asset a command reads (required positional argument).
CLI::Option* add_asset_argument(CLI::App& app, std::string& path,
                                const std::string& help = "asset file (.cbk)");

// --threads N: worker threads, one meaning in every command: 0 (the default) all cores, N > 0 at
// most N. Anything else is exit 1, "--threads: must be a whole number >= 0 (0: all cores), got
// 'TEXT'". `help` says what the threads do.
CLI::Option* add_threads_option(CLI::App& app, int& threads, const std::string& help);

// --tables auto|raw|compressed: which Integral-Radiance tables answer, one meaning in every
// command (eval, render, query radiance): auto, the default, the compressed tables when the asset
// has them and else the raw ones (what a renderer reads); raw or compressed only those (exit 2
// when the asset lacks them). Any other word is exit 1. `scope` prefixes the help ("radiance: ").
CLI::Option* add_tables_option(CLI::App& app, eval::TableChoice& choice,
                               const std::string& scope = "");

// --image-size W,H: the camera's pixels, integers in [1, 16384] (the vertical field of view is
// kept, so the aspect follows W/H). Throws CLI::ValidationError("--image-size", ...) otherwise.
std::array<int, 2> parse_image_size(const std::string& text);

// What a number list must look like.
struct NumberListRule {
  std::string expected;              // for the message "expected EXPECTED, got 'TEXT'"
  std::size_t count = 0;             // exactly this many numbers; 0: at least one
  bool integers = false;             // whole numbers only
  bool positive = false;             // every number > 0
  double min = -1e308, max = 1e308;  // every number in [min, max]
};

// "a,b,c": numbers separated by commas and/or whitespace, each finite and the whole item (no
// trailing characters), checked against `rule`. Throws CLI::ValidationError(option,
// "expected RULE.expected, got 'TEXT'") otherwise.
std::vector<double> parse_number_list(const std::string& text, const std::string& option,
                                      const NumberListRule& rule);

// "x,y,z": three finite numbers (not normalised).
std::array<double, 3> parse_vec3(const std::string& text, const std::string& option);

// "x,y,z": a direction: three finite numbers, not all zero (not normalised; the caller decides
// whether the length matters), except that a vector whose largest component is above 1e150 or
// below 1e-150 is divided by it (its squared length would overflow or underflow). Throws
// CLI::ValidationError naming the option otherwise.
std::array<double, 3> parse_direction(const std::string& text, const std::string& option);

// --max-memory S of `bake` and `batch`: a size as cache::parse_size reads it (500M, 10G, 123456
// bytes; powers of 1024); empty: `default_share` of pipeline::machine_memory_bytes() (physical RAM
// or the cgroup limit; bake uses all of it, batch 80 %). Throws Error(Usage) (exit 1) naming
// --max-memory for a malformed size or 0, as for the other size options.
uint64_t max_memory_option(const std::string& text, double default_share);

// Longest --time-budget accepted: one day (render, docs/rendering.md "Bounds").
inline constexpr double kMaxTimeBudgetSeconds = 86400.0;

// Samples one `eval` may ask for: --spp x --repeat at most 2^32 (about 15 minutes at the 0.2 us
// per brute-force sample measured; docs/evaluator.md). Throws CLI::ValidationError otherwise.
inline constexpr double kMaxEvalSamples = 4294967296.0;  // 2^32

}  // namespace clothbake::cli

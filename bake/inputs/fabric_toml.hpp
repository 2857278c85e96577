// Strict reading of the fabric description's TOML: every key is checked against the schema (with a
// "did you mean" suggestion for unknown keys), every value against its type and valid range, and
// every error names the file, line, column and the dotted key ("yarn[1].roughness").
//
// Safe on untrusted input: all failures throw clothbake::Error(ExitCode::Input); nothing here
// touches files other than the TOML text handed in.
#pragma once

#include <toml++/toml.h>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fabric/fabric.hpp"

namespace clothbake::inputs {

// Levenshtein distance (insert, delete, substitute; each cost 1). Case-sensitive.
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate closest to `word` by edit distance when it is close enough to be a plausible typo
// (distance <= 2, or <= a third of the word's length for longer words); empty otherwise.
std::string closest_match(std::string_view word, const std::vector<std::string>& candidates);

// Deepest nesting accepted in a TOML file: dotted keys, table headers, arrays and inline tables
// together (clothbake's own files nest at most 4 levels). toml++ bounds nested values (256) but not
// dotted keys, and walking a tree 30 000 levels deep overflows the stack.
inline constexpr std::size_t kMaxTomlDepth = 128;

// Refuses characters outside ASCII where TOML 1.0 does not allow them (outside strings and
// comments, and after a line-ending backslash in a multi-line basic string), naming
// FILE:LINE:COLUMN and the code point, and text that nests deeper than kMaxTomlDepth (dotted keys,
// headers, arrays, inline tables: counted on the text, before any parser recurses), naming where.
// Safe on any bytes; throws Error(Input).
void check_toml_characters(std::string_view text, const std::string& file);

// Parses TOML text after check_toml_characters. `file` is used in messages only. Syntax errors
// throw Error(Input) with "FILE:LINE:COLUMN: TOML syntax error: ...".
toml::table parse_toml_text(std::string_view text, const std::string& file);

// An interval of valid values, printed in messages as "(0, 1]", "[1, 64]" or "> 0".
struct Range {
  double lo = -1e300;
  double hi = 1e300;
  bool lo_open = false;
  bool hi_open = false;
  bool contains(double v) const;
  std::string describe() const;
};

// One table of the description (the root, [bake], a [[yarn]] entry, ...) with its dotted name.
class TomlSection {
 public:
  TomlSection(const toml::table& table, std::string file, std::string prefix);

  // Throws on the first key not in `allowed` (in file order), suggesting the closest allowed key.
  void check_keys(const std::vector<std::string>& allowed) const;

  bool has(std::string_view key) const { return table_->contains(key); }

  // Typed getters: empty when the key is absent; throw naming key, line and expectation when the
  // value has the wrong type or lies outside `range`. Integers are accepted where reals are
  // expected.
  std::optional<double> real(std::string_view key, const Range& range) const;
  std::optional<int64_t> integer(std::string_view key, int64_t lo, int64_t hi) const;
  std::optional<bool> boolean(std::string_view key) const;
  std::optional<std::string> string(std::string_view key) const;
  // A string that must be one of `choices`; the message lists them (and suggests the closest).
  std::optional<std::string> choice(std::string_view key,
                                    const std::vector<std::string>& choices) const;
  // A colour: one number (grey) or an array of three numbers, each inside `range`.
  std::optional<Rgb> rgb(std::string_view key, const Range& range) const;
  // An array of colours, each an array of three numbers inside `range` (at least one colour).
  std::optional<std::vector<Rgb>> rgb_list(std::string_view key, const Range& range) const;
  // An array of exactly `count` numbers, each inside `range` (a position, a direction, a size).
  std::optional<std::vector<double>> numbers(std::string_view key, std::size_t count,
                                             const Range& range) const;
  // An array of strings (at least one).
  std::optional<std::vector<std::string>> string_array(std::string_view key) const;

  // A sub-table ([bake], [weave.warp]); empty when absent; throws when the key is not a table.
  std::optional<TomlSection> table(std::string_view key) const;
  // An array of tables ([[yarn]]); empty when absent; throws when the key is something else.
  std::optional<std::vector<TomlSection>> table_array(std::string_view key) const;

  // "bake.resolution" for key "resolution" of section "bake"; "resolution" for the root.
  std::string dotted(std::string_view key) const;
  const std::string& file() const { return file_; }
  const std::string& prefix() const { return prefix_; }
  // "FILE:LINE:COLUMN" of the key's value (or of the section when the key is absent).
  std::string where(std::string_view key) const;
  // Throws Error(Input) with "WHERE: DOTTED-KEY MESSAGE".
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;

 private:
  const toml::node& node(std::string_view key) const;
  const toml::table* table_;
  std::string file_;
  std::string prefix_;
};

// "FILE:LINE:COLUMN" of a node (just FILE when toml++ has no position for it).
std::string toml_location(const std::string& file, const toml::source_region& source);

// The physical length units descriptions use (fabric [tile] units, a scene's units), and their
// length in mm; 0 for "tile" and anything else (no physical size).
inline const std::vector<std::string> kPhysicalLengthUnits = {"um", "mm", "cm", "m", "in"};
double length_unit_in_mm(std::string_view unit);

}  // namespace clothbake::inputs

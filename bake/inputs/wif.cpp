// WIF 1.1 import (docs/weaves.md, "WIF import"): INI-style sections, row sections with 1-based
// thread numbers, defaults from [WARP]/[WEFT], and the drawdown from threading and lifts.
#include "bake/inputs/wif.hpp"
#include "bake/inputs/fabric_files.hpp"

#include <algorithm>
#include <bitset>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "common/diagnostics.hpp"
#include "common/error.hpp"

namespace clothbake {

namespace {

constexpr std::size_t kMaxWifBytes = 64u << 20;   // far above any real draft
using ShaftSet = std::bitset<kMaxWifShafts + 1>;  // bit s = shaft s (1-based)

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b])))
    ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1])))
    --e;
  return s.substr(b, e - b);
}

// Upper- or lower-cases and collapses runs of blanks to one space ("Rising  Shed" = "rising shed").
std::string normalise(const std::string& s, bool upper) {
  std::string out;
  bool blank = false;
  for (char c : trim(s)) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      blank = true;
      continue;
    }
    if (blank) out += ' ';
    blank = false;
    out += char(upper ? std::toupper(static_cast<unsigned char>(c))
                      : std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

struct KeyLine {
  int line = 0;
  std::string key;    // as written, trimmed
  std::string value;  // trimmed
};

struct Section {
  std::string name;  // normalised: upper case, aliases resolved
  int header_line = 0;
  std::map<std::string, KeyLine> keys;  // by lower-cased key
};

// Sections of WIF 1.1 that carry nothing this importer needs: skipped silently.
const std::set<std::string> kIgnoredSections = {"CONTENTS",
                                                "TRANSLATIONS",
                                                "NOTES",
                                                "WARP SYMBOL PALETTE",
                                                "WEFT SYMBOL PALETTE",
                                                "WARP SYMBOL TABLE",
                                                "WEFT SYMBOL TABLE",
                                                "WARP SYMBOLS",
                                                "WEFT SYMBOLS",
                                                "WARP SPACING ZOOM",
                                                "WEFT SPACING ZOOM",
                                                "WARP THICKNESS ZOOM",
                                                "WEFT THICKNESS ZOOM",
                                                "BITMAP IMAGE",
                                                "BITMAP IMAGE DATA",
                                                "BITMAP FILE",
                                                "DESIGN"};
// Sections read here.
const std::set<std::string> kReadSections = {
    "WIF",         "TEXT",         "WEAVING",      "WARP",           "WEFT",          "THREADING",
    "TIEUP",       "TREADLING",    "LIFTPLAN",     "COLOR PALETTE",  "COLOR TABLE",   "WARP COLORS",
    "WEFT COLORS", "WARP SPACING", "WEFT SPACING", "WARP THICKNESS", "WEFT THICKNESS"};

std::string canonical_section(const std::string& raw) {
  std::string name = normalise(raw, true);
  if (name == "TIE-UP" || name == "TIE UP") return "TIEUP";
  if (name == "LIFT PLAN" || name == "LIFT-PLAN") return "LIFTPLAN";
  if (name == "COLOUR TABLE") return "COLOR TABLE";
  if (name == "COLOUR PALETTE") return "COLOR PALETTE";
  return name;
}

class Parser {
 public:
  Parser(const std::string& text, std::string path) : path_(std::move(path)) { split(text); }

  WifDraft run();

 private:
  // --- messages -------------------------------------------------------------------------------
  [[noreturn]] void fail_at(const std::string& section, int line, const std::string& what) const {
    throw_input_error(path_ + ": [" + section + "] line " + std::to_string(line) + ": " + what);
  }
  [[noreturn]] void fail_in(const std::string& section, const std::string& what) const {
    throw_input_error(path_ + ": [" + section + "]: " + what);
  }
  [[noreturn]] void fail(const std::string& what) const { throw_input_error(path_ + ": " + what); }
  void warning(const std::string& what) {
    const std::string message = path_ + ": " + what;
    draft_.warnings.push_back(message);
    warn(message);
  }

  // --- lexical layer --------------------------------------------------------------------------
  void split(const std::string& text);
  const Section* section(const std::string& name) const {
    auto it = sections_.find(name);
    return it == sections_.end() || it->second.keys.empty() ? nullptr : &it->second;
  }
  const KeyLine* key(const Section* s, const std::string& lower_key) const {
    if (!s) return nullptr;
    auto it = s->keys.find(lower_key);
    return it == s->keys.end() ? nullptr : &it->second;
  }

  // --- values ---------------------------------------------------------------------------------
  // Numbers and booleans may carry a trailing "; comment".
  static std::string numeric_text(const std::string& value) {
    return trim(value.substr(0, value.find(';')));
  }
  long integer(const std::string& sec, const KeyLine& k, long lo, long hi, const std::string& what);
  double real(const std::string& sec, const KeyLine& k, const std::string& text,
              const std::string& what);
  bool boolean(const std::string& sec, const KeyLine& k);
  std::vector<long> integer_list(const std::string& sec, const KeyLine& k, const std::string& what);
  int thread_number(const std::string& sec, const KeyLine& k, int count, const std::string& system);

  // --- semantic layer -------------------------------------------------------------------------
  struct System {  // [WARP] or [WEFT]
    std::string name;
    int threads = 0;
    double mm_per_unit = 0;                    // 0 = no Units given
    std::optional<double> spacing, thickness;  // in Units
    std::optional<int> color;                  // 1-based index into the colour table
  };
  void read_header();
  System read_system(const std::string& name, const std::string& rows_a, const std::string& rows_b);
  void read_weaving(int max_shaft_used, int max_treadle_used);
  std::vector<ShaftSet> read_shaft_rows(const std::string& sec, int count,
                                        const std::string& system, int limit,
                                        const std::string& limit_name, std::vector<int>& lines);
  void read_colors(const System& warp, const System& weft);
  void read_geometry(const System& warp, const System& weft);
  weave::YarnGeometry base_geometry(const System& s, const std::optional<double>& spacing,
                                    const std::optional<double>& thickness) const;
  int max_index_in(const std::string& sec);
  int max_value_in(const std::string& sec, const std::string& what);

  std::string path_;
  std::map<std::string, Section> sections_;
  WifDraft draft_;
};

void Parser::split(const std::string& raw_text) {
  std::string text = raw_text;
  if (text.size() >= 3 && static_cast<unsigned char>(text[0]) == 0xEF &&
      static_cast<unsigned char>(text[1]) == 0xBB && static_cast<unsigned char>(text[2]) == 0xBF)
    text.erase(0, 3);  // UTF-8 byte order mark
  std::istringstream in(text);
  std::string line;
  int number = 0;
  Section* current = nullptr;
  bool skipping = false;
  bool warned_preamble = false;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string t = trim(line);
    if (t.empty() || t[0] == ';') continue;
    if (t[0] == '[') {
      if (t.back() != ']')
        throw_input_error(path_ + ": line " + std::to_string(number) +
                          ": malformed section header '" + t + "' (no closing ']')");
      const std::string name = canonical_section(t.substr(1, t.size() - 2));
      if (name.empty())
        throw_input_error(path_ + ": line " + std::to_string(number) + ": empty section name");
      current = nullptr;
      skipping = true;
      if (name.rfind("PRIVATE", 0) == 0) {
        warning("line " + std::to_string(number) + ": skipping private section [" + name + "]");
      } else if (kIgnoredSections.count(name)) {
        // Known, carries nothing needed here.
      } else if (!kReadSections.count(name)) {
        warning("line " + std::to_string(number) + ": skipping unknown section [" + name + "]");
      } else {
        skipping = false;
        auto [it, inserted] = sections_.try_emplace(name);
        if (!inserted)
          warning("[" + name + "] line " + std::to_string(number) +
                  ": the section appears again (first at line " +
                  std::to_string(it->second.header_line) + "); its keys are merged");
        else
          it->second.header_line = number;
        it->second.name = name;
        current = &it->second;
      }
      continue;
    }
    if (skipping) continue;
    if (!current) {
      if (!warned_preamble)
        warning("line " + std::to_string(number) + ": text before the first section is ignored");
      warned_preamble = true;
      continue;
    }
    const std::size_t eq = t.find('=');
    if (eq == std::string::npos)
      fail_at(current->name, number, "expected Key=Value, found '" + t + "'");
    KeyLine k{number, trim(t.substr(0, eq)), trim(t.substr(eq + 1))};
    if (k.key.empty()) fail_at(current->name, number, "missing key before '='");
    const std::string lower = normalise(k.key, false);
    auto [it, inserted] = current->keys.try_emplace(lower, k);
    if (!inserted) {
      warning("[" + current->name + "] line " + std::to_string(number) + ": key '" + k.key +
              "' repeats line " + std::to_string(it->second.line) + "; the later value is used");
      it->second = k;
    }
  }
}

long Parser::integer(const std::string& sec, const KeyLine& k, long lo, long hi,
                     const std::string& what) {
  const std::string t = numeric_text(k.value);
  long v = 0;
  auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size())
    fail_at(sec, k.line, k.key + " = '" + k.value + "' is not a whole number (" + what + ")");
  if (v < lo || v > hi)
    fail_at(sec, k.line,
            k.key + " = " + std::to_string(v) + " is outside " + std::to_string(lo) + ".." +
                std::to_string(hi) + " (" + what + ")");
  return v;
}

double Parser::real(const std::string& sec, const KeyLine& k, const std::string& text,
                    const std::string& what) {
  const std::string t = trim(text);
  double v = 0;
  const char* begin = t.data();
  if (!t.empty() && t[0] == '+') ++begin;
  auto [ptr, ec] = std::from_chars(begin, t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || ptr != t.data() + t.size() || !std::isfinite(v))
    fail_at(sec, k.line, k.key + " = '" + k.value + "' is not a number (" + what + ")");
  return v;
}

bool Parser::boolean(const std::string& sec, const KeyLine& k) {
  const std::string t = normalise(numeric_text(k.value), false);
  if (t == "true" || t == "yes" || t == "on" || t == "1") return true;
  if (t == "false" || t == "no" || t == "off" || t == "0") return false;
  fail_at(sec, k.line,
          k.key + " = '" + k.value + "' is not a boolean (true/false, yes/no, on/off, 1/0)");
}

std::vector<long> Parser::integer_list(const std::string& sec, const KeyLine& k,
                                       const std::string& what) {
  std::vector<long> out;
  const std::string t = numeric_text(k.value);
  if (t.empty()) return out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = t.find(',', start);
    const std::string item =
        trim(t.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    long v = 0;
    auto [ptr, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc() || ptr != item.data() + item.size() || v < 0)
      fail_at(sec, k.line,
              "'" + k.value + "' is not a comma-separated list of " + what + " numbers");
    out.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

int Parser::thread_number(const std::string& sec, const KeyLine& k, int count,
                          const std::string& system) {
  long v = 0;
  auto [ptr, ec] = std::from_chars(k.key.data(), k.key.data() + k.key.size(), v);
  if (ec != std::errc() || ptr != k.key.data() + k.key.size() || v < 1)
    fail_at(sec, k.line,
            "'" + k.key + "' is not a " + system + " thread number (thread numbers start at 1)");
  if (v > count)
    fail_at(sec, k.line,
            system + " thread " + std::to_string(v) + " is beyond [" + system +
                "] Threads=" + std::to_string(count));
  return int(v);
}

int Parser::max_index_in(const std::string& sec) {
  int max_index = 0;
  if (const Section* s = section(sec)) {
    for (const auto& [lower, k] : s->keys) {
      long v = 0;
      auto [ptr, ec] = std::from_chars(k.key.data(), k.key.data() + k.key.size(), v);
      if (ec != std::errc() || ptr != k.key.data() + k.key.size() || v < 1)
        fail_at(sec, k.line, "'" + k.key + "' is not a thread number (thread numbers start at 1)");
      if (v > weave::kMaxRepeat)
        fail_at(sec, k.line,
                "thread " + std::to_string(v) + " is beyond the largest repeat (" +
                    std::to_string(weave::kMaxRepeat) + " threads)");
      max_index = std::max(max_index, int(v));
    }
  }
  return max_index;
}

int Parser::max_value_in(const std::string& sec, const std::string& what) {
  long max_value = 0;
  if (const Section* s = section(sec))
    for (const auto& [lower, k] : s->keys)
      for (long v : integer_list(sec, k, what))
        max_value = std::max(max_value, v);
  return int(std::min<long>(max_value, kMaxWifShafts + 1L));
}

void Parser::read_header() {
  if (!sections_.count("WIF")) fail("not a WIF file: there is no [WIF] section");
  const Section* wif = section("WIF");
  if (const KeyLine* v = key(wif, "version")) {
    draft_.version = v->value;
    if (v->value != "1.1" && v->value != "1.0")
      warning("[WIF] line " + std::to_string(v->line) + ": Version=" + v->value +
              " is not 1.0 or 1.1; reading it as 1.1");
  } else {
    warning("[WIF]: no Version; reading the file as WIF 1.1");
  }
  if (const KeyLine* p = key(wif, "source program")) draft_.source_program = p->value;
  if (const KeyLine* t = key(section("TEXT"), "title")) draft_.title = t->value;
}

Parser::System Parser::read_system(const std::string& name, const std::string& rows_a,
                                   const std::string& rows_b) {
  System s;
  s.name = name;
  const Section* sec = section(name);
  if (const KeyLine* t = key(sec, "threads")) {
    s.threads = int(integer(name, *t, 0, weave::kMaxRepeat, "number of threads"));
    if (s.threads == 0) fail_at(name, t->line, "Threads=0: the draft has no " + name + " threads");
  } else {
    // Not given: the highest thread number listed (the spec requires Threads; drafts omit it).
    int inferred = 0;
    for (const std::string& rows :
         {rows_a, rows_b, name + " COLORS", name + " SPACING", name + " THICKNESS"})
      inferred = std::max(inferred, max_index_in(rows));
    if (inferred == 0)
      fail_in(name, "no Threads, and no [" + rows_a + "] entries to count them from");
    warning("[" + name + "]: no Threads; using " + std::to_string(inferred) +
            ", the highest thread number listed");
    s.threads = inferred;
  }
  if (const KeyLine* u = key(sec, "units")) {
    const std::string unit = normalise(numeric_text(u->value), false);
    if (unit == "decipoints" || unit == "decipoint")
      s.mm_per_unit = 25.4 / 720.0;
    else if (unit == "inches" || unit == "inch")
      s.mm_per_unit = 25.4;
    else if (unit == "centimeters" || unit == "centimetres" || unit == "centimeter" ||
             unit == "centimetre")
      s.mm_per_unit = 10.0;
    else if (unit == "millimeters" || unit == "millimetres")
      s.mm_per_unit = 1.0;
    else
      fail_at(name, u->line, "Units = '" + u->value + "' is not Decipoints, Inches or Centimeters");
  }
  auto length = [&](const char* k, std::optional<double>& out) {
    if (const KeyLine* line = key(sec, k)) {
      const double v = real(name, *line, numeric_text(line->value), "a length in Units");
      if (v < 0) fail_at(name, line->line, line->key + " = " + line->value + " is negative");
      if (v == 0)
        warning("[" + name + "] line " + std::to_string(line->line) + ": " + line->key +
                "=0 is ignored; the default is used");
      else
        out = v;
    }
  };
  length("spacing", s.spacing);
  length("thickness", s.thickness);
  if (const KeyLine* c = key(sec, "color")) {
    // A bare index, or "index,R,G,B" in old files: the index counts.
    const std::vector<long> list = integer_list(name, *c, "colour index");
    if (list.empty() || list[0] < 1)
      fail_at(name, c->line, "Color = '" + c->value + "' is not a colour table index");
    s.color = int(std::min<long>(list[0], 1L << 30));
  }
  return s;
}

void Parser::read_weaving(int max_shaft_used, int max_treadle_used) {
  const Section* w = section("WEAVING");
  if (const KeyLine* k = key(w, "shafts")) {
    draft_.shafts = int(integer("WEAVING", *k, 1, kMaxWifShafts, "number of shafts"));
  } else {
    if (max_shaft_used < 1) fail_in("WEAVING", "no Shafts, and no shaft is used");
    if (max_shaft_used > kMaxWifShafts)
      fail_in("WEAVING",
              "no Shafts, and shafts beyond " + std::to_string(kMaxWifShafts) + " are used");
    warning("[WEAVING]: no Shafts; using " + std::to_string(max_shaft_used) +
            ", the highest shaft used");
    draft_.shafts = max_shaft_used;
  }
  if (const KeyLine* k = key(w, "treadles")) {
    draft_.treadles = int(integer("WEAVING", *k, 0, kMaxWifShafts, "number of treadles"));
  } else if (max_treadle_used > 0) {
    if (max_treadle_used > kMaxWifShafts)
      fail_in("WEAVING",
              "no Treadles, and treadles beyond " + std::to_string(kMaxWifShafts) + " are used");
    warning("[WEAVING]: no Treadles; using " + std::to_string(max_treadle_used) +
            ", the highest treadle used");
    draft_.treadles = max_treadle_used;
  }
  // WIF 1.1 makes Rising Shed optional; drafting programs assume a rising (jack) shed.
  if (const KeyLine* k = key(w, "rising shed")) draft_.rising_shed = boolean("WEAVING", *k);
}

std::vector<ShaftSet> Parser::read_shaft_rows(const std::string& sec, int count,
                                              const std::string& system, int limit,
                                              const std::string& limit_name,
                                              std::vector<int>& lines) {
  std::vector<ShaftSet> rows(static_cast<std::size_t>(count));
  lines.assign(std::size_t(count), 0);
  if (const Section* s = section(sec)) {
    for (const auto& [lower, k] : s->keys) {
      const int index = thread_number(sec, k, count, system);
      lines[std::size_t(index - 1)] = k.line;
      for (long v : integer_list(sec, k, limit_name)) {
        if (v == 0) continue;  // 0 = none
        if (v > limit)
          fail_at(sec, k.line,
                  limit_name + " " + std::to_string(v) + " is beyond [WEAVING] " +
                      (limit_name == "shaft" ? "Shafts=" : "Treadles=") + std::to_string(limit));
        rows[std::size_t(index - 1)].set(std::size_t(v));
      }
    }
  }
  return rows;
}

weave::YarnGeometry Parser::base_geometry(const System& s, const std::optional<double>& spacing,
                                          const std::optional<double>& thickness) const {
  weave::YarnGeometry g;
  const double unit = s.mm_per_unit > 0 ? s.mm_per_unit : 25.4;  // inches when Units is missing
  if (spacing) g.spacing_mm = *spacing * unit;
  if (thickness) {
    // Thickness is the yarn's visible width: the width fraction of its space, and a yarn
    // flattened to half its width in the cloth (docs/weaves.md).
    const double thickness_mm = *thickness * unit;
    g.width = std::min(1.0, thickness_mm / g.spacing_mm);
    g.height_mm = 0.5 * thickness_mm;
  } else {
    g.height_mm = 0.3 * g.spacing_mm;  // the default 0.15 mm : 0.5 mm proportion
  }
  return g;
}

void Parser::read_geometry(const System& warp, const System& weft) {
  for (const System* s : {&warp, &weft}) {
    const bool any = s->spacing || s->thickness || section(s->name + " SPACING") ||
                     section(s->name + " THICKNESS");
    if (any && s->mm_per_unit == 0)
      warning("[" + s->name + "]: no Units for the spacing/thickness; assuming Inches");
  }
  auto per_system = [&](const System& s, weave::YarnGeometry& common,
                        std::vector<weave::YarnGeometry>& per_thread) {
    common = base_geometry(s, s.spacing, s.thickness);
    const std::string spacing_sec = s.name + " SPACING", thickness_sec = s.name + " THICKNESS";
    if (!section(spacing_sec) && !section(thickness_sec)) return;
    std::vector<std::optional<double>> spacing(std::size_t(s.threads), s.spacing),
        thickness(std::size_t(s.threads), s.thickness);
    for (auto [sec, values] : {std::pair{spacing_sec, &spacing}, {thickness_sec, &thickness}}) {
      if (const Section* rows = section(sec)) {
        for (const auto& [lower, k] : rows->keys) {
          const int index = thread_number(sec, k, s.threads, s.name);
          const double v = real(sec, k, numeric_text(k.value), "a length in Units");
          if (v <= 0) fail_at(sec, k.line, "'" + k.value + "' is not a positive length");
          (*values)[std::size_t(index - 1)] = v;
        }
      }
    }
    per_thread.resize(std::size_t(s.threads));
    for (int i = 0; i < s.threads; ++i)
      per_thread[std::size_t(i)] =
          base_geometry(s, spacing[std::size_t(i)], thickness[std::size_t(i)]);
  };
  per_system(warp, draft_.spec.warp, draft_.spec.end_geometry);
  per_system(weft, draft_.spec.weft, draft_.spec.pick_geometry);
}

void Parser::read_colors(const System& warp, const System& weft) {
  // Palette range: "min,max" (or a lone "max"); 0,255 when missing.
  double lo = 0, hi = 255;
  const Section* palette = section("COLOR PALETTE");
  const Section* table_sec = section("COLOR TABLE");
  if (const KeyLine* r = key(palette, "range")) {
    const std::vector<long> range = integer_list("COLOR PALETTE", *r, "range");
    if (range.size() == 1) {
      hi = double(range[0]);
    } else if (range.size() == 2) {
      lo = double(range[0]);
      hi = double(range[1]);
    } else {
      fail_at("COLOR PALETTE", r->line, "Range = '" + r->value + "' is not 'min,max'");
    }
    if (!(hi > lo)) fail_at("COLOR PALETTE", r->line, "Range = '" + r->value + "' is empty");
  } else if (table_sec) {
    warning("[COLOR PALETTE]: no Range; assuming 0,255");
  }
  std::map<long, Rgb> table;
  std::map<long, int> table_lines;
  if (table_sec) {
    for (const auto& [lower, k] : table_sec->keys) {
      long index = 0;
      auto [ptr, ec] = std::from_chars(k.key.data(), k.key.data() + k.key.size(), index);
      if (ec != std::errc() || ptr != k.key.data() + k.key.size() || index < 1)
        fail_at("COLOR TABLE", k.line, "'" + k.key + "' is not a colour number (1-based)");
      const std::string t = numeric_text(k.value);
      std::vector<double> channels;
      std::size_t start = 0;
      while (true) {
        const std::size_t comma = t.find(',', start);
        channels.push_back(
            real("COLOR TABLE", k,
                 t.substr(start, comma == std::string::npos ? std::string::npos : comma - start),
                 "an R,G,B channel"));
        if (comma == std::string::npos) break;
        start = comma + 1;
      }
      if (channels.size() != 3)
        fail_at("COLOR TABLE", k.line, "'" + k.value + "' is not an R,G,B triple");
      Rgb rgb{};
      bool clamped = false;
      for (int c = 0; c < 3; ++c) {
        double v = (channels[std::size_t(c)] - lo) / (hi - lo);
        if (v < 0 || v > 1) clamped = true;
        v = std::clamp(v, 0.0, 1.0);
        // WIF colours are display (sRGB-encoded) values; the albedo map is linear.
        rgb[std::size_t(c)] = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
      }
      if (clamped)
        warning("[COLOR TABLE] line " + std::to_string(k.line) + ": colour " + k.value +
                " is outside the palette Range " + std::to_string(long(lo)) + ".." +
                std::to_string(long(hi)) + "; clamped");
      table[index] = rgb;
      table_lines[index] = k.line;
    }
    if (const KeyLine* e = key(palette, "entries")) {
      const long entries = integer("COLOR PALETTE", *e, 0, 1L << 30, "number of colours");
      if (!table.empty() && table.rbegin()->first > entries)
        warning("[COLOR TABLE] line " + std::to_string(table_lines[table.rbegin()->first]) +
                ": colour " + std::to_string(table.rbegin()->first) +
                " is beyond [COLOR PALETTE] Entries=" + std::to_string(entries));
    }
  }
  auto lookup = [&](long index, const std::string& sec, int line) -> Rgb {
    auto it = table.find(index);
    if (it == table.end())
      fail_at(sec, line, "colour " + std::to_string(index) + " is not in the [COLOR TABLE]");
    return it->second;
  };
  auto per_system = [&](const System& s, std::vector<Rgb>& colors) {
    const std::string rows_sec = s.name + " COLORS";
    const Section* rows = section(rows_sec);
    if (!s.color && !rows) return;  // white
    Rgb fallback{1, 1, 1};
    if (s.color) fallback = lookup(*s.color, s.name, key(section(s.name), "color")->line);
    colors.assign(std::size_t(s.threads), fallback);
    if (!rows) return;
    for (const auto& [lower, k] : rows->keys) {
      const int index = thread_number(rows_sec, k, s.threads, s.name);
      const std::vector<long> list = integer_list(rows_sec, k, "colour index");
      if (list.empty() || list[0] < 1)
        fail_at(rows_sec, k.line, "'" + k.value + "' is not a colour table index");
      colors[std::size_t(index - 1)] = lookup(list[0], rows_sec, k.line);
    }
  };
  per_system(warp, draft_.spec.end_colors);
  per_system(weft, draft_.spec.pick_colors);
}

std::string shaft_list(const ShaftSet& set) {
  std::string out;
  for (std::size_t s = 1; s < set.size(); ++s)
    if (set.test(s)) {
      if (!out.empty()) out += ',';
      out += std::to_string(s);
    }
  return out.empty() ? "none" : out;
}

WifDraft Parser::run() {
  read_header();
  const bool have_threading = section("THREADING") != nullptr;
  const bool have_treadling = section("TREADLING") != nullptr;
  const bool have_tieup = section("TIEUP") != nullptr;
  const bool have_liftplan = section("LIFTPLAN") != nullptr;
  if (!have_threading)
    fail(
        "there is no [THREADING] (or it is empty): the draft does not say which shaft each end "
        "is on");
  if (!have_liftplan && !have_treadling)
    fail(
        "there is neither a [TREADLING] nor a [LIFTPLAN] (or they are empty): the draft does not "
        "say which shafts rise on each pick");
  if (have_treadling && !have_tieup && !have_liftplan)
    fail("[TREADLING] needs a [TIEUP] (or use a [LIFTPLAN]): without it the treadles lift nothing");
  // Tie-up plus treadling is the loom's own record; a lift plan is the fallback (WIF format
  // guide, "Tie-up and treadling vs lift plan").
  const bool use_treadling = have_treadling && have_tieup;
  draft_.from_liftplan = !use_treadling;

  const System warp = read_system("WARP", "THREADING", "THREADING");
  const System weft = read_system("WEFT", use_treadling ? "TREADLING" : "LIFTPLAN",
                                  have_liftplan ? "LIFTPLAN" : "TREADLING");
  read_weaving(std::max({max_value_in("THREADING", "shaft"), max_value_in("TIEUP", "shaft"),
                         max_value_in("LIFTPLAN", "shaft")}),
               max_value_in("TREADLING", "treadle"));

  std::vector<int> threading_lines, pick_lines, unused;
  const std::vector<ShaftSet> threading =
      read_shaft_rows("THREADING", warp.threads, "WARP", draft_.shafts, "shaft", threading_lines);

  std::vector<ShaftSet> lifts(static_cast<std::size_t>(weft.threads));
  std::vector<ShaftSet> liftplan;
  std::vector<int> liftplan_lines;
  if (have_liftplan)
    liftplan =
        read_shaft_rows("LIFTPLAN", weft.threads, "WEFT", draft_.shafts, "shaft", liftplan_lines);
  std::string pick_section = "LIFTPLAN";
  if (use_treadling) {
    pick_section = "TREADLING";
    // Tie-up: treadle -> shafts. Entries for treadles beyond the declared count are unused by
    // any valid treadling; drafting programs write them, so they are skipped with a warning.
    std::vector<ShaftSet> tieup(static_cast<std::size_t>(draft_.treadles) + 1);
    for (const auto& [lower, k] : section("TIEUP")->keys) {
      long treadle = 0;
      auto [ptr, ec] = std::from_chars(k.key.data(), k.key.data() + k.key.size(), treadle);
      if (ec != std::errc() || ptr != k.key.data() + k.key.size() || treadle < 1)
        fail_at("TIEUP", k.line, "'" + k.key + "' is not a treadle number (treadles start at 1)");
      const std::vector<long> shafts = integer_list("TIEUP", k, "shaft");
      if (treadle > draft_.treadles) {
        warning("[TIEUP] line " + std::to_string(k.line) + ": treadle " + std::to_string(treadle) +
                " is beyond [WEAVING] Treadles=" + std::to_string(draft_.treadles) + "; ignored");
        continue;
      }
      for (long s : shafts) {
        if (s == 0) continue;
        if (s > draft_.shafts)
          fail_at("TIEUP", k.line,
                  "shaft " + std::to_string(s) +
                      " is beyond [WEAVING] Shafts=" + std::to_string(draft_.shafts));
        tieup[std::size_t(treadle)].set(std::size_t(s));
      }
    }
    const std::vector<ShaftSet> treadling =
        read_shaft_rows("TREADLING", weft.threads, "WEFT", draft_.treadles, "treadle", pick_lines);
    for (int p = 0; p < weft.threads; ++p)
      for (int t = 1; t <= draft_.treadles; ++t)
        if (treadling[std::size_t(p)].test(std::size_t(t)))
          lifts[std::size_t(p)] |= tieup[std::size_t(t)];
    if (have_liftplan && liftplan != lifts)
      warning(
          "[LIFTPLAN] disagrees with [TIEUP] + [TREADLING]; the tie-up and treadling are "
          "used");
  } else {
    lifts = liftplan;
    pick_lines = liftplan_lines;
  }

  // Drawdown: warp up iff a shaft of the end is lifted (rising shed); a sinking shed lowers the
  // listed shafts instead, so the result is inverted.
  weave::WeaveMatrix m = weave::make_matrix(weft.threads, warp.threads, path_);
  for (int p = 0; p < m.picks; ++p)
    for (int e = 0; e < m.ends; ++e) {
      const bool selected = (threading[std::size_t(e)] & lifts[std::size_t(p)]).any();
      m.set(p, e, selected == draft_.rising_shed);
    }

  // Weavability, reported against the line that made the thread float.
  const std::string face_up = draft_.rising_shed ? "rises" : "sinks";
  for (int e = 0; e < m.ends; ++e) {
    int up = 0;
    for (int p = 0; p < m.picks; ++p)
      up += m.warp_up(p, e);
    if (up != 0 && up != m.picks) continue;
    const std::string floats = up == 0 ? "under every pick" : "over every pick";
    if (threading[std::size_t(e)].none())
      fail_in("THREADING", "end " + std::to_string(e + 1) +
                               " is not threaded (no entry or 0), so it floats " + floats +
                               " and is not held");
    fail_at("THREADING", threading_lines[std::size_t(e)],
            "end " + std::to_string(e + 1) + " (shafts " + shaft_list(threading[std::size_t(e)]) +
                ") never interlaces: it floats " + floats + " of the repeat");
  }
  for (int p = 0; p < m.picks; ++p) {
    int up = 0;
    for (int e = 0; e < m.ends; ++e)
      up += m.warp_up(p, e);
    if (up != 0 && up != m.ends) continue;
    const std::string floats = up == m.ends ? "under every end" : "over every end";
    if (pick_lines[std::size_t(p)] == 0)
      fail_in(pick_section, "pick " + std::to_string(p + 1) + " has no entry (no shaft " + face_up +
                                "), so it floats " + floats + " and is not held");
    fail_at(pick_section, pick_lines[std::size_t(p)],
            "pick " + std::to_string(p + 1) + " (lifts shafts " +
                shaft_list(lifts[std::size_t(p)]) + ") never interlaces: it floats " + floats +
                " of the repeat");
  }

  draft_.spec.matrix = std::move(m);
  read_colors(warp, weft);
  read_geometry(warp, weft);
  weave::validate_weave_spec(draft_.spec, path_);

  draft_.threading.resize(std::size_t(warp.threads));
  for (int e = 0; e < warp.threads; ++e)
    for (int s = 1; s <= draft_.shafts; ++s)
      if (threading[std::size_t(e)].test(std::size_t(s)))
        draft_.threading[std::size_t(e)].push_back(s - 1);
  draft_.lifts.resize(std::size_t(weft.threads));
  for (int p = 0; p < weft.threads; ++p)
    for (int s = 1; s <= draft_.shafts; ++s)
      if (lifts[std::size_t(p)].test(std::size_t(s))) draft_.lifts[std::size_t(p)].push_back(s - 1);
  return std::move(draft_);
}

}  // namespace

WifDraft parse_wif(const std::string& text, const std::string& path_for_messages) {
  if (text.size() > kMaxWifBytes)
    throw_input_error(path_for_messages + ": the file is larger than " +
                      std::to_string(kMaxWifBytes >> 20) + " MiB; not a weaving draft");
  Parser parser(text, path_for_messages);
  return parser.run();
}

WifDraft read_wif(const std::string& path) {
  // A directory is not "larger than 64 MiB" and a FIFO would block: regular files only (a missing
  // file keeps its "cannot open" message below).
  std::error_code exists_error;
  if (std::filesystem::exists(path, exists_error)) inputs::require_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_input_error(path + ": cannot open the WIF file");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw_input_error(path + ": cannot read the WIF file");
  if (std::uint64_t(size) > kMaxWifBytes)
    throw_input_error(path + ": the file is larger than " + std::to_string(kMaxWifBytes >> 20) +
                      " MiB; not a weaving draft");
  in.seekg(0);
  std::string text(std::size_t(size), '\0');
  if (!in.read(text.data(), size)) throw_input_error(path + ": cannot read the WIF file");
  return parse_wif(text, path);
}

}  // namespace clothbake

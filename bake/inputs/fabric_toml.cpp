#include "bake/inputs/fabric_toml.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <utility>

#include "common/error.hpp"

namespace clothbake::inputs {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  // Two-row dynamic programme; keys are short, so O(|a| |b|) is nothing.
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t substitute = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitute});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::string closest_match(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::size_t(-1);
  // A truncated or extended key ("spacing" for "spacing_mm") is a typo whatever its distance.
  if (word.size() >= 3)
    for (const auto& candidate : candidates)
      if (candidate.size() != word.size() &&
          (candidate.rfind(word, 0) == 0 || std::string_view(word).rfind(candidate, 0) == 0) &&
          std::min(candidate.size(), word.size()) >= 3)
        return candidate;
  for (const auto& candidate : candidates) {
    std::size_t d = edit_distance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  std::size_t allowed = std::max<std::size_t>(2, word.size() / 3);
  return best_distance <= allowed ? best : std::string();
}

std::string toml_location(const std::string& file, const toml::source_region& source) {
  if (source.begin.line == 0) return file;
  return fmt::format("{}:{}:{}", file, source.begin.line, source.begin.column);
}

namespace {

// Code point of the UTF-8 sequence at text[i] (U+FFFD for a malformed one) and its length.
std::pair<char32_t, std::size_t> decode_utf8(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned lead = byte(i);
  const std::size_t length = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : lead >= 0xC0 ? 2 : 1;
  if (length == 1 || i + length > text.size()) return {U'\uFFFD', 1};
  char32_t c = lead & (0x3Fu >> (length - 1));
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return {U'\uFFFD', 1};
    c = (c << 6) | (byte(i + k) & 0x3F);
  }
  return {c, length};
}

bool ascii_blank(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

// toml++ never sees a character outside ASCII (docs/hardening.md, "Fuzzing"): every code point
// U+0080-U+FFFF of the text is replaced by its placeholder U+100000 + (c - 0x80) in Supplementary
// Private Use Area-B, beyond U+FEFF, where toml++'s Unicode tests answer at their first comparison.
// Line and column numbers stay those of the file (one code point for one). Parsed keys, string
// values and error messages get the original characters back. A file holding a placeholder code
// point itself is refused (the mapping would not be one to one).
constexpr char32_t kPlaceholderBase = 0x100000;
constexpr char32_t kFirstMapped = 0x80, kLastMapped = 0xFFFF;

void append_utf8(std::string& out, char32_t c) {
  if (c < 0x80) {
    out += char(c);
  } else if (c < 0x800) {
    out += char(0xC0 | (c >> 6));
    out += char(0x80 | (c & 0x3F));
  } else if (c < 0x10000) {
    out += char(0xE0 | (c >> 12));
    out += char(0x80 | ((c >> 6) & 0x3F));
    out += char(0x80 | (c & 0x3F));
  } else {
    out += char(0xF0 | (c >> 18));
    out += char(0x80 | ((c >> 12) & 0x3F));
    out += char(0x80 | ((c >> 6) & 0x3F));
    out += char(0x80 | (c & 0x3F));
  }
}

// The well-formed UTF-8 sequence at text[i] (shortest form, no surrogate, at most U+10FFFF): its
// code point and length; length 0 when it is not one.
std::pair<char32_t, std::size_t> decode_utf8_strict(std::string_view text, std::size_t i) {
  const auto [c, length] = decode_utf8(text, i);
  const unsigned lead = static_cast<unsigned char>(text[i]);
  if (lead < 0x80) return {char32_t(lead), 1};
  const std::size_t shortest = c < 0x80 ? 1 : c < 0x800 ? 2 : c < 0x10000 ? 3 : 4;
  const bool ok = length > 1 && lead < 0xF8 && length == shortest &&
                  !(c >= 0xD800 && c <= 0xDFFF) && c <= 0x10FFFF;
  return {c, ok ? length : 0};
}

// FILE:LINE:COLUMN of byte offset `at` (columns count characters, as toml++'s do).
std::string text_location(std::string_view text, std::size_t at, const std::string& file) {
  std::size_t line = 1, column = 1;
  for (std::size_t k = 0; k < at; ++k) {
    if (text[k] == '\n')
      line += 1, column = 1;
    else if ((static_cast<unsigned char>(text[k]) & 0xC0) != 0x80)
      ++column;
  }
  return fmt::format("{}:{}:{}", file, line, column);
}

constexpr bool is_placeholder(char32_t c) {
  return c >= kPlaceholderBase && c <= kPlaceholderBase + (kLastMapped - kFirstMapped);
}

}  // namespace

void check_toml_characters(std::string_view text, const std::string& file) {
  // TOML 1.0 allows characters outside ASCII only inside strings and comments; refusing them
  // elsewhere here gives the message a person can act on (toml++ itself would only ever see their
  // placeholders, see parse_toml_text).
  enum class In { Code, Comment, Basic, MultiBasic, Literal, MultiLiteral };
  In in = In::Code;
  const auto refuse = [&](std::size_t at, const char* where) {
    const char32_t c = decode_utf8(text, at).first;
    throw Error(ExitCode::Input,
                fmt::format("{}: character U+{:04X} {}: TOML allows characters outside ASCII only "
                            "inside strings and comments",
                            text_location(text, at, file), static_cast<std::uint32_t>(c), where));
  };
  const auto starts = [&](std::size_t i, std::string_view s) {
    return text.substr(i, s.size()) == s;
  };
  const auto quote_run = [&](std::size_t i, char quote) {
    std::size_t k = i;
    while (k < text.size() && k - i < 5 && text[k] == quote)
      ++k;
    return k - i;
  };
  // Nesting, counted over the code (an upper bound of the parsed tree's depth): a table header's
  // dotted key, then per open array or inline table of a value one level plus the dots of the key
  // before it. toml++ caps nested values but not dotted keys, and every walk of the tree (its own
  // destructor included) recurses once per level.
  std::vector<std::size_t> open;                         // depth at each open '[' or '{' of a value
  std::size_t header_depth = 0, dots = 0, key_dots = 0;  // key_dots: of the key before '='
  bool line_start = true, in_header = false, header_fresh = false;
  const auto depth_base = [&] {
    return !open.empty() ? open.back() : in_header ? std::size_t(0) : header_depth;
  };
  const auto check_depth = [&](std::size_t at, std::size_t depth) {
    if (depth > kMaxTomlDepth)
      throw Error(ExitCode::Input,
                  fmt::format("{}: keys, arrays and inline tables nest more than {} levels deep",
                              text_location(text, at, file), kMaxTomlDepth));
  };
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    std::size_t step = 1;
    switch (in) {
      case In::Code:
        if (static_cast<unsigned char>(c) >= 0x80) refuse(i, "outside a string or comment");
        if (c == '\n') {
          line_start = true, dots = key_dots = 0;
        } else if (c == '[' && in_header && header_fresh) {
          header_fresh = false;  // the second '[' of "[[array.of.tables]]"
        } else if (c == '[' && open.empty() && line_start) {
          in_header = header_fresh = true, dots = 0;
        } else if (c == '[' || c == '{') {
          open.push_back(depth_base() + key_dots + dots + 1), dots = key_dots = 0;
          check_depth(i, open.back());
        } else if (c == ']' && in_header) {
          header_depth = dots + 1, in_header = false, dots = 0;
        } else if ((c == ']' || c == '}') && !open.empty()) {
          open.pop_back(), dots = key_dots = 0;
        } else if (c == '=') {
          key_dots = dots, dots = 0;
        } else if (c == ',') {
          dots = key_dots = 0;
        } else if (c == '.') {
          check_depth(i, depth_base() + key_dots + ++dots + 1);
        }
        if (c != '\n' && !ascii_blank(c)) line_start = false;
        if (c != '[' && !ascii_blank(c)) header_fresh = false;
        if (c == '#')
          in = In::Comment;
        else if (starts(i, "\"\"\""))
          in = In::MultiBasic, step = 3;
        else if (c == '"')
          in = In::Basic;
        else if (starts(i, "'''"))
          in = In::MultiLiteral, step = 3;
        else if (c == '\'')
          in = In::Literal;
        break;
      case In::Comment:
        if (c == '\n') in = In::Code, line_start = true, dots = key_dots = 0;
        break;
      case In::Basic:
        if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n')
          step = 2;
        else if (c == '"' || c == '\n')
          in = In::Code;  // a newline ends it (toml++ reports it)
        break;
      case In::MultiBasic:
        if (c == '\\' && i + 1 < text.size()) {
          const char next = text[i + 1];
          if (static_cast<unsigned char>(next) >= 0x80)
            refuse(i + 1, "after a backslash in a multi-line string");
          if (ascii_blank(next)) {  // a line-ending backslash: toml++ skips the blanks after it
            std::size_t j = i + 1;
            while (j < text.size() && ascii_blank(text[j]))
              ++j;
            if (j < text.size() && static_cast<unsigned char>(text[j]) >= 0x80)
              refuse(j, "after a line-ending backslash in a multi-line string");
            i = j;
            continue;
          }
          step = 2;
        } else if (starts(i, "\"\"\"")) {
          in = In::Code, step = quote_run(i, '"');  // up to two quotes before the closing three
        }
        break;
      case In::Literal:
        if (c == '\'' || c == '\n') in = In::Code;
        break;
      case In::MultiLiteral:
        if (starts(i, "'''")) in = In::Code, step = quote_run(i, '\'');
        break;
    }
    i += step;
  }
}

namespace {

// The text toml++ is given: every code point U+0080-U+FFFF replaced by its placeholder. Refuses
// (Error(Input), naming FILE:LINE:COLUMN) bytes that are not well-formed UTF-8 (TOML files must
// be) and placeholder code points in the file itself.
std::string placeholders_for(std::string_view text, const std::string& file) {
  std::string out;
  out.reserve(text.size() + text.size() / 4);
  for (std::size_t i = 0; i < text.size();) {
    const auto [c, length] = decode_utf8_strict(text, i);
    if (length == 0)
      throw Error(ExitCode::Input,
                  fmt::format("{}: byte 0x{:02X} is not well-formed UTF-8 (TOML "
                              "files are UTF-8)",
                              text_location(text, i, file), static_cast<unsigned char>(text[i])));
    if (is_placeholder(c))
      throw Error(ExitCode::Input,
                  fmt::format("{}: character U+{:04X} is not accepted (clothbake's TOML reader "
                              "uses U+100000-U+10FF7F internally)",
                              text_location(text, i, file), static_cast<std::uint32_t>(c)));
    if (c >= kFirstMapped && c <= kLastMapped)
      append_utf8(out, kPlaceholderBase + (c - kFirstMapped));
    else
      out.append(text.substr(i, length));
    i += length;
  }
  return out;
}

// The inverse of placeholders_for on text that toml++ produced (keys, strings, messages).
std::string original_characters(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto [c, length] = decode_utf8_strict(text, i);
    if (length > 0 && is_placeholder(c)) {
      append_utf8(out, kFirstMapped + (c - kPlaceholderBase));
      i += length;
    } else {
      const std::size_t n = length > 0 ? length : 1;
      out.append(text.substr(i, n));
      i += n;
    }
  }
  return out;
}

bool has_placeholder(std::string_view s) {
  // Every placeholder's UTF-8 form starts with the byte 0xF4 (U+100000-U+10FFFF).
  return s.find('\xF4') != std::string_view::npos;
}

void restore_characters(toml::node& node);

void restore_characters(toml::table& table) {
  std::vector<std::string> renamed;
  for (auto&& [key, value] : table) {
    restore_characters(value);
    if (has_placeholder(key.str())) renamed.emplace_back(key.str());
  }
  for (const std::string& old_name : renamed) {
    const auto it = table.find(old_name);
    toml::key restored(original_characters(old_name), it->first.source());
    toml::node& value = it->second;
    table.insert_or_assign(std::move(restored), std::move(value));
    table.erase(old_name);
  }
}

void restore_characters(toml::node& node) {
  if (toml::table* t = node.as_table()) {
    restore_characters(*t);
  } else if (toml::array* a = node.as_array()) {
    for (toml::node& element : *a)
      restore_characters(element);
  } else if (toml::value<std::string>* s = node.as_string()) {
    if (has_placeholder(s->get())) s->get() = original_characters(s->get());
  }
}

}  // namespace

toml::table parse_toml_text(std::string_view text, const std::string& file) {
  check_toml_characters(text, file);
  const std::string mapped = placeholders_for(text, file);
  try {
    toml::table table = toml::parse(mapped, file);
    restore_characters(table);
    return table;
  } catch (const toml::parse_error& e) {
    throw Error(ExitCode::Input,
                fmt::format("{}: TOML syntax error: {}", toml_location(file, e.source()),
                            original_characters(e.description())));
  }
}

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  bool above = lo_open ? v > lo : v >= lo;
  bool below = hi_open ? v < hi : v <= hi;
  return above && below;
}

std::string Range::describe() const {
  bool unbounded_above = hi >= 1e300;
  bool unbounded_below = lo <= -1e300;
  if (unbounded_above && unbounded_below) return "any finite number";
  if (unbounded_above) return fmt::format("{} {}", lo_open ? ">" : ">=", lo);
  if (unbounded_below) return fmt::format("{} {}", hi_open ? "<" : "<=", hi);
  return fmt::format("{}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
}

namespace {

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    default:
      return "nothing";
  }
}

// The value as written, for messages ("-0.2", "\"abc\"").
std::string show(const toml::node& node) {
  std::ostringstream out;
  node.visit([&](const auto& value) {
    if constexpr (toml::is_string<decltype(value)>)
      out << '"' << value.get() << '"';
    else if constexpr (toml::is_floating_point<decltype(value)>)
      out << fmt::format("{}",
                         value.get());  // shortest form that round-trips: -0.2, not -0.2000...1
    else if constexpr (toml::is_integer<decltype(value)> || toml::is_boolean<decltype(value)>)
      out << value;
    else if constexpr (toml::is_array<decltype(value)>)
      out << "[...]";
    else if constexpr (toml::is_table<decltype(value)>)
      out << "{...}";
    else
      out << value;
  });
  return out.str();
}

bool node_number(const toml::node& node, double& out) {
  if (auto i = node.as_integer()) {
    out = double(i->get());
    return true;
  }
  if (auto f = node.as_floating_point()) {
    out = f->get();
    return true;
  }
  return false;
}

}  // namespace

TomlSection::TomlSection(const toml::table& table, std::string file, std::string prefix)
    : table_(&table), file_(std::move(file)), prefix_(std::move(prefix)) {}

std::string TomlSection::dotted(std::string_view key) const {
  if (prefix_.empty()) return std::string(key);
  if (key.empty()) return prefix_;
  return prefix_ + "." + std::string(key);
}

std::string TomlSection::where(std::string_view key) const {
  if (const toml::node* n = table_->get(key)) return toml_location(file_, n->source());
  return toml_location(file_, table_->source());
}

void TomlSection::fail(std::string_view key, const std::string& message) const {
  // "color[1] = 1.5 ..." for element messages, "color must be ..." otherwise.
  const char* separator = !message.empty() && message[0] == '[' ? "" : " ";
  throw Error(ExitCode::Input,
              fmt::format("{}: {}{}{}", where(key), dotted(key), separator, message));
}

const toml::node& TomlSection::node(std::string_view key) const {
  return *table_->get(key);
}

void TomlSection::check_keys(const std::vector<std::string>& allowed) const {
  const toml::node* first_bad = nullptr;
  std::string first_key;
  for (const auto& [key, value] : *table_) {
    if (std::find(allowed.begin(), allowed.end(), key.str()) != allowed.end()) continue;
    const auto& pos = value.source().begin;
    bool earlier = !first_bad || pos.line < first_bad->source().begin.line ||
                   (pos.line == first_bad->source().begin.line &&
                    pos.column < first_bad->source().begin.column);
    if (earlier) {
      first_bad = &value;
      first_key = std::string(key.str());
    }
  }
  if (!first_bad) return;
  std::string suggestion = closest_match(first_key, allowed);
  std::string hint;
  if (!suggestion.empty()) {
    hint = fmt::format("; did you mean '{}'?", dotted(suggestion));
  } else {
    std::string all;
    for (const auto& k : allowed)
      all += (all.empty() ? "" : ", ") + k;
    hint = fmt::format("; valid keys{}: {}", prefix_.empty() ? "" : " in [" + prefix_ + "]", all);
  }
  throw Error(ExitCode::Input,
              fmt::format("{}: unknown key '{}'{}", toml_location(file_, first_bad->source()),
                          dotted(first_key), hint));
}

std::optional<double> TomlSection::real(std::string_view key, const Range& range) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  double v = 0;
  if (!node_number(n, v))
    fail(key, fmt::format("must be a number ({}), got {} ({})", range.describe(), type_name(n),
                          show(n)));
  if (!range.contains(v))
    fail(key, fmt::format("= {} is out of range; valid range is {}", show(n), range.describe()));
  return v;
}

std::optional<int64_t> TomlSection::integer(std::string_view key, int64_t lo, int64_t hi) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  auto i = n.as_integer();
  if (!i)
    fail(key,
         fmt::format("must be an integer in [{}, {}], got {} ({})", lo, hi, type_name(n), show(n)));
  int64_t v = i->get();
  if (v < lo || v > hi)
    fail(key, fmt::format("= {} is out of range; valid range is [{}, {}]", v, lo, hi));
  return v;
}

std::optional<bool> TomlSection::boolean(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  auto b = n.as_boolean();
  if (!b) fail(key, fmt::format("must be true or false, got {} ({})", type_name(n), show(n)));
  return b->get();
}

std::optional<std::string> TomlSection::string(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  auto s = n.as_string();
  if (!s) fail(key, fmt::format("must be a string, got {} ({})", type_name(n), show(n)));
  return s->get();
}

std::optional<std::string> TomlSection::choice(std::string_view key,
                                               const std::vector<std::string>& choices) const {
  auto s = string(key);
  if (!s) return s;
  if (std::find(choices.begin(), choices.end(), *s) != choices.end()) return s;
  std::string all;
  for (const auto& c : choices)
    all += (all.empty() ? "\"" : ", \"") + c + "\"";
  std::string suggestion = closest_match(*s, choices);
  fail(key,
       fmt::format("= \"{}\" is not valid; expected one of {}{}", *s, all,
                   suggestion.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", suggestion)));
}

std::optional<Rgb> TomlSection::rgb(std::string_view key, const Range& range) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  double grey = 0;
  if (node_number(n, grey)) {
    if (!range.contains(grey))
      fail(key, fmt::format("= {} is out of range; valid range is {}", show(n), range.describe()));
    return Rgb{grey, grey, grey};
  }
  const toml::array* arr = n.as_array();
  if (!arr || arr->size() != 3)
    fail(key, fmt::format("must be a number or an array of 3 numbers [r, g, b], got {}{}",
                          type_name(n), arr ? fmt::format(" of {} elements", arr->size()) : ""));
  Rgb out{};
  for (std::size_t c = 0; c < 3; ++c) {
    double v = 0;
    if (!node_number(*arr->get(c), v))
      fail(key, fmt::format("[{}] must be a number, got {}", c, type_name(*arr->get(c))));
    if (!range.contains(v))
      fail(key,
           fmt::format("[{}] = {} is out of range; valid range is {}", c, v, range.describe()));
    out[c] = v;
  }
  return out;
}

std::optional<std::vector<double>> TomlSection::numbers(std::string_view key, std::size_t count,
                                                        const Range& range) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  const toml::array* arr = n.as_array();
  if (!arr || arr->size() != count)
    fail(key, fmt::format("must be an array of {} numbers, got {}{}", count, type_name(n),
                          arr ? fmt::format(" of {} elements", arr->size()) : ""));
  std::vector<double> out(count);
  for (std::size_t c = 0; c < count; ++c) {
    double v = 0;
    if (!node_number(*arr->get(c), v))
      fail(key, fmt::format("[{}] must be a number, got {}", c, type_name(*arr->get(c))));
    if (!range.contains(v))
      fail(key,
           fmt::format("[{}] = {} is out of range; valid range is {}", c, v, range.describe()));
    out[c] = v;
  }
  return out;
}

std::optional<std::vector<Rgb>> TomlSection::rgb_list(std::string_view key,
                                                      const Range& range) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  const toml::array* arr = n.as_array();
  if (!arr || arr->empty())
    fail(key, fmt::format("must be a non-empty array of colours [[r, g, b], ...], got {}",
                          arr ? "an empty array" : type_name(n)));
  std::vector<Rgb> out;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::array* colour = arr->get(i)->as_array();
    if (!colour || colour->size() != 3)
      fail(key, fmt::format("[{}] must be an array of 3 numbers [r, g, b], got {}", i,
                            type_name(*arr->get(i))));
    Rgb rgb{};
    for (std::size_t c = 0; c < 3; ++c) {
      double v = 0;
      if (!node_number(*colour->get(c), v))
        fail(key,
             fmt::format("[{}][{}] must be a number, got {}", i, c, type_name(*colour->get(c))));
      if (!range.contains(v))
        fail(key, fmt::format("[{}][{}] = {} is out of range; valid range is {}", i, c, v,
                              range.describe()));
      rgb[c] = v;
    }
    out.push_back(rgb);
  }
  return out;
}

std::optional<std::vector<std::string>> TomlSection::string_array(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  const toml::array* arr = n.as_array();
  if (!arr || arr->empty())
    fail(key, fmt::format("must be a non-empty array of strings, got {}",
                          arr ? "an empty array" : type_name(n)));
  std::vector<std::string> out;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    auto s = arr->get(i)->as_string();
    if (!s) fail(key, fmt::format("[{}] must be a string, got {}", i, type_name(*arr->get(i))));
    out.push_back(s->get());
  }
  return out;
}

std::optional<TomlSection> TomlSection::table(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  const toml::table* t = n.as_table();
  if (!t) fail(key, fmt::format("must be a table ([{}]), got {}", dotted(key), type_name(n)));
  return TomlSection(*t, file_, dotted(key));
}

std::optional<std::vector<TomlSection>> TomlSection::table_array(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = node(key);
  const toml::array* arr = n.as_array();
  if (!arr || !arr->is_array_of_tables())
    fail(key, fmt::format("must be an array of tables ([[{}]] sections), got {}", dotted(key),
                          type_name(n)));
  std::vector<TomlSection> out;
  for (std::size_t i = 0; i < arr->size(); ++i)
    out.emplace_back(*arr->get(i)->as_table(), file_, fmt::format("{}[{}]", dotted(key), i));
  return out;
}

double length_unit_in_mm(std::string_view unit) {
  if (unit == "um") return 1e-3;
  if (unit == "mm") return 1.0;
  if (unit == "cm") return 10.0;
  if (unit == "m") return 1000.0;
  if (unit == "in") return 25.4;
  return 0.0;  // "tile": no physical size
}

}  // namespace clothbake::inputs

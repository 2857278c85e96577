// The strict TOML layer: edit distance, suggestions, typed getters and their messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "bake/inputs/fabric_toml.hpp"
#include "tests/bake/inputs/test_support.hpp"

namespace clothbake::inputs {
namespace {

using clothbake::testing::error_message;
using ::testing::HasSubstr;

TEST(EditDistance, ClassicCases) {
  EXPECT_EQ(edit_distance("", ""), 0u);
  EXPECT_EQ(edit_distance("abc", ""), 3u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);  // the textbook example
  EXPECT_EQ(edit_distance("flaw", "lawn"), 2u);
  EXPECT_EQ(edit_distance("roughnes", "roughness"), 1u);
  EXPECT_EQ(edit_distance("colour", "color"), 1u);
  // Symmetric.
  EXPECT_EQ(edit_distance("resolutoin", "resolution"), edit_distance("resolution", "resolutoin"));
  EXPECT_EQ(edit_distance("resolutoin", "resolution"), 2u);  // a transposition costs 2
}

TEST(ClosestMatch, SuggestsOnlyPlausibleTypos) {
  std::vector<std::string> keys = {"roughness", "optical_thickness", "color", "name"};
  EXPECT_EQ(closest_match("roughnes", keys), "roughness");
  EXPECT_EQ(closest_match("colour", keys), "color");
  EXPECT_EQ(closest_match("optical_thicknes", keys), "optical_thickness");
  EXPECT_EQ(closest_match("zzzzzzzz", keys), "");
  EXPECT_EQ(closest_match("x", {}), "");
}

TEST(Range, ContainsAndDescribe) {
  Range r{0.0, 1.0, true, false};
  EXPECT_FALSE(r.contains(0.0));
  EXPECT_TRUE(r.contains(1e-9));
  EXPECT_TRUE(r.contains(1.0));
  EXPECT_FALSE(r.contains(1.0 + 1e-12));
  EXPECT_FALSE(r.contains(std::nan("")));
  EXPECT_FALSE(r.contains(INFINITY));
  EXPECT_EQ(r.describe(), "(0, 1]");
  EXPECT_EQ((Range{0.0, 1.0}).describe(), "[0, 1]");
  EXPECT_EQ((Range{0.0, 1e300, true, false}).describe(), "> 0");
}

TEST(ParseToml, SyntaxErrorNamesLineAndColumn) {
  std::string msg = error_message([] { parse_toml_text("a = 1\nb = = 2\n", "f.toml"); });
  EXPECT_THAT(msg, HasSubstr("f.toml:2:"));
  EXPECT_THAT(msg, HasSubstr("TOML syntax error"));
}

// toml++ 3.3 reaches __builtin_unreachable when it asks whether U+021A (and most code points in
// U+00A1-U+0499) is whitespace; the 4-byte input below was found by the fabric TOML fuzzer.
TEST(ParseToml, NonAsciiOutsideStringsIsRefusedBeforeTomlppSeesIt) {
  std::string msg = error_message([] { parse_toml_text("5\xC8\x9A ", "f.toml"); });
  EXPECT_THAT(msg, HasSubstr("f.toml:1:2: character U+021A outside a string or comment"));
  msg = error_message([] { parse_toml_text("a = 1\n[b]\nk\xC3\xA9 = 2\n", "f.toml"); });
  EXPECT_THAT(msg, HasSubstr("f.toml:3:2: character U+00E9"));
  // After a line-ending backslash toml++ asks the same question of the next character.
  msg = error_message([] {
    parse_toml_text(
        "s = \"\"\"a\\  \n  \xC8\x9A"
        "b\"\"\"\n",
        "f.toml");
  });
  EXPECT_THAT(msg, HasSubstr("f.toml:2:3: character U+021A after a line-ending backslash"));
  msg = error_message([] { parse_toml_text("s = \"\"\"a\\\xC8\x9A\"\"\"\n", "f.toml"); });
  EXPECT_THAT(msg, HasSubstr("f.toml:1:10: character U+021A after a backslash"));
}

TEST(ParseToml, NonAsciiInsideStringsAndCommentsIsKept) {
  const std::string text =
      "# caf\xC3\xA9 \"quoted\" \xC8\x9A\n"
      "a = \"\xC8\x9A \\\" \xC8\x9A\"  # \xC8\x9A\n"
      "b = 'x \xC8\x9A'\n"
      "c = \"\"\"\n\xC8\x9A \"\" \xC8\x9A\"\"\"\"  # a quote before the closing three: \"\xC8\x9A\n"
      "d = '''\xC8\x9A'' \xC8\x9A'''''\n"
      "e = \"\"\"x\\\n   y \xC8\x9A\"\"\"\n"
      "[\"k\xC3\xA9y\"]\n"
      "f = 1\n";
  toml::table t = parse_toml_text(text, "f.toml");
  EXPECT_EQ(t["a"].value_or(std::string()), "\xC8\x9A \" \xC8\x9A");
  EXPECT_EQ(t["b"].value_or(std::string()), "x \xC8\x9A");
  EXPECT_EQ(t["c"].value_or(std::string()), "\xC8\x9A \"\" \xC8\x9A\"");
  EXPECT_EQ(t["d"].value_or(std::string()), "\xC8\x9A'' \xC8\x9A''");
  EXPECT_EQ(t["e"].value_or(std::string()), "xy \xC8\x9A");
  EXPECT_EQ(t["k\xC3\xA9y"]["f"].value_or(0), 1);
}

// toml++ is given placeholders for every character outside ASCII (docs/hardening.md, "Fuzzing"),
// so an invalid document can no longer lead it to a non-ASCII character outside a string: this
// input (found by the fabric TOML fuzzer after the lexical guard above) makes toml++ read the
// quotes after "-" as part of a bad value and test U+021A for whitespace.
TEST(ParseToml, NonAsciiInAnInvalidValueIsASyntaxErrorNamingTheOriginalCharacters) {
  const std::string msg = error_message([] {
    parse_toml_text(
        "nameneme =-\"\"\"\"\"@\xC8\x9A"
        "b\"\"\"\n",
        "f.toml");
  });
  EXPECT_THAT(msg, HasSubstr("f.toml:1:"));
  EXPECT_THAT(msg, HasSubstr("TOML syntax error"));
  EXPECT_THAT(msg, ::testing::Not(HasSubstr("\xF4")));  // no placeholder reaches a message
}

TEST(ParseToml, KeysAndStringsKeepEveryCharacter) {
  // Latin, Greek, Cyrillic, CJK, a presentation form, an emoji (beyond the BMP, not mapped), and
  // the last BMP code point before the placeholders' range.
  const std::string text =
      "\"k\xC3\xA9y \xCE\xB1\" = \"v\xC3\xA0lue \xD0\x96 \xE3\x81\x82 \xEF\xAC\xB0 "
      "\xF0\x9F\xA7\xB5\"\n"
      "lit = 'l\xC3\xAF\xEF\xBF\xBD'\n"
      "arr = [\"\xC3\xA9\", ['\xC3\xBC'], {\"\xC3\xB1\" = \"\xC3\xA7\"}]\n"
      "[\"t\xC3\xA4\" . 'b\xC3\xB6']\n"
      "multi = \"\"\"\n\xC3\xA9\n\"\"\"\n";
  toml::table t = parse_toml_text(text, "f.toml");
  EXPECT_EQ(t["k\xC3\xA9y \xCE\xB1"].value_or(std::string()),
            "v\xC3\xA0lue \xD0\x96 \xE3\x81\x82 \xEF\xAC\xB0 \xF0\x9F\xA7\xB5");
  EXPECT_EQ(t["lit"].value_or(std::string()), "l\xC3\xAF\xEF\xBF\xBD");
  EXPECT_EQ(t["arr"][0].value_or(std::string()), "\xC3\xA9");
  EXPECT_EQ(t["arr"][1][0].value_or(std::string()), "\xC3\xBC");
  EXPECT_EQ(t["arr"][2]["\xC3\xB1"].value_or(std::string()), "\xC3\xA7");
  EXPECT_EQ(t["t\xC3\xA4"]["b\xC3\xB6"]["multi"].value_or(std::string()), "\xC3\xA9\n");
  // Restored keys keep their place in the file.
  const toml::node* renamed = t.get("k\xC3\xA9y \xCE\xB1");
  ASSERT_NE(renamed, nullptr);
  EXPECT_EQ(renamed->source().begin.line, 1u);
}

TEST(ParseToml, ColumnsCountTheFilesOwnCharacters) {
  // The same positions as for ASCII text of the same length in characters, whatever each
  // character's UTF-8 length (2, 3 and 4 bytes below).
  const std::string wide = error_message(
      [] { parse_toml_text("a = \"\xC3\xA9\xE3\x81\x82\xF0\x9F\xA7\xB5\" = 1 x\n", "f.toml"); });
  const std::string ascii = error_message([] { parse_toml_text("a = \"eee\" = 1 x\n", "f.toml"); });
  EXPECT_EQ(wide.substr(0, wide.find(" TOML")), ascii.substr(0, ascii.find(" TOML")));
  EXPECT_THAT(wide, HasSubstr("f.toml:1:11:"));
  for (const char* text : {"\"\xC3\xA9\xC3\xA9\" = 1\nb = [1, \"\xC3\xA9\", 3]\n",
                           "\"ee\" = 1\nb = [1, \"e\", 3]\n"}) {
    toml::table t = parse_toml_text(text, "f.toml");
    const toml::node* third = t["b"][2].node();
    ASSERT_NE(third, nullptr);
    EXPECT_EQ(third->source().begin.line, 2u);
    EXPECT_EQ(third->source().begin.column, 14u);  // b = [1, "é", 3]: the 14th character
  }
}

TEST(ParseToml, RefusesBytesThatAreNotUtf8AndThePlaceholderRange) {
  EXPECT_THAT(error_message([] { parse_toml_text("a = \"\xC3\x28\"\n", "f.toml"); }),
              HasSubstr("f.toml:1:6: byte 0xC3 is not well-formed UTF-8"));
  EXPECT_THAT(error_message([] { parse_toml_text("a = \"\xC0\xA2\"\n", "f.toml"); }),  // overlong
              HasSubstr("f.toml:1:6: byte 0xC0 is not well-formed UTF-8"));
  EXPECT_THAT(error_message([] { parse_toml_text("# \xED\xA0\x80\n", "f.toml"); }),  // surrogate
              HasSubstr("f.toml:1:3: byte 0xED is not well-formed UTF-8"));
  EXPECT_THAT(error_message([] { parse_toml_text("a = \"\xF4\x80\x80\x81\"\n", "f.toml"); }),
              HasSubstr("f.toml:1:6: character U+100001 is not accepted"));
  // Just beyond the placeholders' range is an ordinary character.
  toml::table t = parse_toml_text("a = \"\xF4\x8F\xBE\x80\"\n", "f.toml");
  EXPECT_EQ(t["a"].value_or(std::string()), "\xF4\x8F\xBE\x80");
}

// Nesting is bounded on the text, before toml++ or any walk of its tree recurses: 40 000-level
// dotted keys and headers (a stack overflow in restore_characters before) and inline tables whose
// keys are dotted are refused naming the place; the deepest accepted is kMaxTomlDepth, counted over
// headers, keys, arrays and inline tables together, and ordinary files pass.
TEST(ParseToml, NestingDeeperThanTheLimitIsRefusedBeforeParsing) {
  auto dotted = [](std::size_t n) {  // a key of n segments: n levels
    std::string k = "a";
    for (std::size_t i = 1; i < n; ++i)
      k += ".a";
    return k;
  };
  const std::string deep_key = dotted(40000) + " = 1\n";
  EXPECT_THAT(error_message([&] { parse_toml_text(deep_key, "f.toml"); }),
              HasSubstr("f.toml:1:256: keys, arrays and inline tables nest more than 128 levels"));
  const std::string deep_header = "x = 1\n[" + dotted(40000) + "]\n";
  EXPECT_THAT(error_message([&] { parse_toml_text(deep_header, "f.toml"); }),
              HasSubstr("f.toml:2:257: keys, arrays and inline tables nest more than 128"));
  std::string inline_tables = "x = ";  // 50 inline tables of 4-level keys: 250 levels
  for (int i = 0; i < 50; ++i)
    inline_tables += "{a.b.c.d = ";
  inline_tables += "1" + std::string(50, '}') + "\n";
  EXPECT_THAT(error_message([&] { parse_toml_text(inline_tables, "f.toml"); }),
              HasSubstr("nest more than 128 levels"));
  // A header's depth carries to its keys: 100 + 29 levels is one too many, 100 + 28 fits.
  const std::string header = "[" + dotted(100) + "]\n";
  EXPECT_THAT(error_message([&] { parse_toml_text(header + dotted(29) + " = 1\n", "f.toml"); }),
              HasSubstr("f.toml:2:"));
  EXPECT_NO_THROW(parse_toml_text(header + dotted(28) + " = 1\n", "f.toml"));
  EXPECT_NO_THROW(parse_toml_text(dotted(128) + " = 1\n", "f.toml"));
  // Dots in strings, numbers and comments are not nesting; arrays of tables and values are fine.
  std::string ordinary = "s = \"" + std::string(500, '.') + "\" # " + std::string(500, '.') +
                         "\n[[yarn]]\nv = [1.5, 2.5, [3.5]]\n[a.\"b.c\".d]\ne = {f.g = 1.0}\n";
  const toml::table t = parse_toml_text(ordinary, "f.toml");
  EXPECT_EQ(t["a"]["b.c"]["d"]["e"]["f"]["g"].value_or(0.0), 1.0);
}

struct Doc {
  toml::table table;
  TomlSection root;
  explicit Doc(const std::string& text)
      : table(parse_toml_text(text, "d.toml")), root(table, "d.toml", "") {}
};

TEST(TomlSection, UnknownKeyGetsSuggestionWithLocation) {
  Doc doc("[bake]\nresolution = 64\nclustres = 8\n");
  auto bake = doc.root.table("bake");
  ASSERT_TRUE(bake);
  std::string msg = error_message([&] { bake->check_keys({"resolution", "clusters"}); });
  EXPECT_THAT(msg, HasSubstr("d.toml:3:"));
  EXPECT_THAT(msg, HasSubstr("unknown key 'bake.clustres'"));
  EXPECT_THAT(msg, HasSubstr("did you mean 'bake.clusters'?"));
}

TEST(TomlSection, UnknownKeyWithoutSuggestionListsValidKeys) {
  Doc doc("[sheen]\nbanana = 1\n");
  std::string msg = error_message([&] {
    doc.root.table("sheen")->check_keys({"color", "roughness"});
  });
  EXPECT_THAT(msg, HasSubstr("unknown key 'sheen.banana'"));
  EXPECT_THAT(msg, HasSubstr("valid keys in [sheen]: color, roughness"));
}

TEST(TomlSection, FirstUnknownKeyInFileOrderIsReported) {
  // toml++ stores keys sorted; the message must still point at the first one in the file.
  Doc doc("zeta = 1\nalpha = 2\n");
  std::string msg = error_message([&] { doc.root.check_keys({"name"}); });
  EXPECT_THAT(msg, HasSubstr("'zeta'"));
  EXPECT_THAT(msg, HasSubstr("d.toml:1:"));
}

TEST(TomlSection, TypedGetters) {
  Doc doc(
      "r = 0.5\ni = 3\nb = true\ns = \"x\"\ngrey = 0.25\nrgb = [0.1, 0.2, 0.3]\n"
      "list = [[0, 0, 0], [1, 1, 1]]\nwhole = 1\n");
  const auto& s = doc.root;
  EXPECT_EQ(*s.real("r", Range{0, 1}), 0.5);
  EXPECT_EQ(*s.real("whole", Range{0, 1}), 1.0);  // integers are accepted as reals
  EXPECT_EQ(*s.integer("i", 0, 10), 3);
  EXPECT_TRUE(*s.boolean("b"));
  EXPECT_EQ(*s.string("s"), "x");
  EXPECT_EQ(*s.rgb("grey", Range{0, 1}), (Rgb{0.25, 0.25, 0.25}));
  EXPECT_EQ(*s.rgb("rgb", Range{0, 1}), (Rgb{0.1, 0.2, 0.3}));
  EXPECT_EQ(s.rgb_list("list", Range{0, 1})->size(), 2u);
  EXPECT_FALSE(s.real("absent", Range{0, 1}).has_value());
}

TEST(TomlSection, WrongTypeNamesKeyLineAndExpectation) {
  Doc doc("[bake]\nresolution = \"256\"\nratio = 0.5\n");
  auto bake = *doc.root.table("bake");
  std::string msg = error_message([&] { bake.integer("resolution", 4, 8192); });
  EXPECT_THAT(msg, HasSubstr("d.toml:2:"));
  EXPECT_THAT(msg, HasSubstr("bake.resolution must be an integer in [4, 8192], got a string"));
  msg = error_message([&] { bake.integer("ratio", 0, 10); });
  EXPECT_THAT(msg, HasSubstr("bake.ratio must be an integer"));
}

TEST(TomlSection, OutOfRangeNamesValidRange) {
  Doc doc("[[yarn]]\nroughness = -0.2\ncolor = [0.5, 1.5, 0.5]\n");
  auto yarns = *doc.root.table_array("yarn");
  std::string msg = error_message([&] { yarns[0].real("roughness", Range{0, 1, true, false}); });
  EXPECT_THAT(msg, HasSubstr("d.toml:2:"));
  EXPECT_THAT(msg, HasSubstr("yarn[0].roughness = -0.2 is out of range; valid range is (0, 1]"));
  msg = error_message([&] { yarns[0].rgb("color", Range{0, 1}); });
  EXPECT_THAT(msg, HasSubstr("yarn[0].color[1] = 1.5 is out of range"));
}

TEST(TomlSection, ChoiceSuggestsClosest) {
  Doc doc("units = \"mn\"\n");
  std::string msg = error_message([&] { doc.root.choice("units", {"tile", "mm", "cm"}); });
  EXPECT_THAT(msg, HasSubstr("units = \"mn\" is not valid"));
  EXPECT_THAT(msg, HasSubstr("did you mean \"mm\"?"));
}

TEST(TomlSection, TableOfWrongKind) {
  Doc doc("bake = 3\nyarn = 2\n");
  EXPECT_THAT(error_message([&] { doc.root.table("bake"); }), HasSubstr("bake must be a table"));
  EXPECT_THAT(error_message([&] { doc.root.table_array("yarn"); }),
              HasSubstr("yarn must be an array of tables"));
}

}  // namespace
}  // namespace clothbake::inputs

// WIF 1.1 import: drawdowns from tie-up + treadling and from lift plans, sinking sheds, defaults,
// sparse and 1-based rows, multi-shaft threading, private sections, colours, units, and each
// malformed or unweavable draft rejected with the file, section and line.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "bake/inputs/wif.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"

using namespace clothbake;
using namespace clothbake::weave;

namespace {

const std::string kExamples = std::string(CLOTHBAKE_SOURCE_DIR) + "/examples/wif/";
const std::string kData = std::string(CLOTHBAKE_SOURCE_DIR) + "/tests/bake/inputs/data/";

// A 4-shaft straight draw; `body` adds the weaving, weft and lift sections.
std::string draft(const std::string& body, const std::string& warp = "[WARP]\nThreads=4\n") {
  return "[WIF]\nVersion=1.1\nSource Program=test\n\n" + warp +
         "\n[THREADING]\n1=1\n2=2\n3=3\n4=4\n\n" + body;
}

const std::string kTwillTreadled =
    "[WEAVING]\nShafts=4\nTreadles=4\nRising Shed=true\n[WEFT]\nThreads=4\n"
    "[TIEUP]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n[TREADLING]\n1=1\n2=2\n3=3\n4=4\n";
const std::string kTwillLiftplan =
    "[WEAVING]\nShafts=4\nTreadles=4\n[WEFT]\nThreads=4\n"
    "[LIFTPLAN]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n";

WifDraft parse_quiet(const std::string& text, const std::string& path = "test.wif") {
  set_quiet(true);
  take_warnings();
  WifDraft d = parse_wif(text, path);
  set_quiet(false);
  return d;
}

bool has_warning(const WifDraft& d, const std::string& fragment) {
  for (const std::string& w : d.warnings)
    if (w.find(fragment) != std::string::npos) return true;
  return false;
}

// Expects Error(Input) whose message contains every fragment.
void expect_wif_error(const std::function<void()>& fn,
                      std::initializer_list<std::string> fragments) {
  set_quiet(true);
  try {
    fn();
    ADD_FAILURE() << "no error thrown";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input) << e.what();
    for (const std::string& f : fragments)
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
          << "message '" << e.what() << "' lacks '" << f << "'";
  }
  set_quiet(false);
}

double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

}  // namespace

TEST(Wif, TieUpAndTreadlingGiveTheTwillDrawdown) {
  const WifDraft d = parse_quiet(draft(kTwillTreadled));
  EXPECT_EQ(d.spec.matrix, twill(2, 2, false));
  EXPECT_EQ(d.shafts, 4);
  EXPECT_EQ(d.treadles, 4);
  EXPECT_TRUE(d.rising_shed);
  EXPECT_FALSE(d.from_liftplan);
  ASSERT_EQ(d.threading.size(), 4u);
  EXPECT_EQ(d.threading[2], std::vector<int>{2});  // 0-based shafts
  ASSERT_EQ(d.lifts.size(), 4u);
  EXPECT_EQ(d.lifts[3], (std::vector<int>{0, 3}));
  EXPECT_TRUE(d.warnings.empty());
}

TEST(Wif, LiftplanGivesTheSameDrawdown) {
  const WifDraft treadled = parse_quiet(draft(kTwillTreadled));
  const WifDraft lifted = parse_quiet(draft(kTwillLiftplan));
  EXPECT_TRUE(lifted.from_liftplan);
  EXPECT_EQ(lifted.spec.matrix, treadled.spec.matrix);
  EXPECT_EQ(lifted.lifts, treadled.lifts);
  // Both present and agreeing: tie-up + treadling used, no warning.
  const WifDraft both =
      parse_quiet(draft(kTwillTreadled + "[LIFTPLAN]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n"));
  EXPECT_FALSE(both.from_liftplan);
  EXPECT_EQ(both.spec.matrix, treadled.spec.matrix);
  EXPECT_TRUE(both.warnings.empty());
  // Disagreeing: still the tie-up + treadling, with a warning.
  const WifDraft clash = parse_quiet(draft(kTwillTreadled + "[LIFTPLAN]\n1=1\n2=2\n3=3\n4=4\n"));
  EXPECT_EQ(clash.spec.matrix, treadled.spec.matrix);
  EXPECT_TRUE(has_warning(clash, "disagrees"));
}

TEST(Wif, SinkingShedIsTheComplement) {
  std::string sinking = kTwillTreadled;
  sinking.replace(sinking.find("Rising Shed=true"), 16, "Rising Shed=false");
  const WifDraft rising = parse_quiet(draft(kTwillTreadled));
  const WifDraft sunk = parse_quiet(draft(sinking));
  EXPECT_FALSE(sunk.rising_shed);
  EXPECT_EQ(sunk.spec.matrix, rising.spec.matrix.complement());
  // "no"/"off"/"0" are false too; "yes"/"on"/"1" true; case-insensitive.
  for (const char* f : {"no", "OFF", "0", "False"}) {
    std::string text = kTwillTreadled;
    text.replace(text.find("Rising Shed=true"), 16, std::string("rising shed=") + f);
    EXPECT_EQ(parse_quiet(draft(text)).spec.matrix, sunk.spec.matrix) << f;
  }
  for (const char* t : {"yes", "On", "1"}) {
    std::string text = kTwillTreadled;
    text.replace(text.find("Rising Shed=true"), 16, std::string("RISING SHED = ") + t);
    EXPECT_EQ(parse_quiet(draft(text)).spec.matrix, rising.spec.matrix) << t;
  }
}

TEST(Wif, DefaultsAndOmittedEntries) {
  // No Rising Shed (rising), no Threads in [WEFT] (inferred, warned), sparse colour rows falling
  // back to the [WARP] Color, the weft without any colour (white), a treadling entry "0" and a
  // tie-up treadle that is never pressed.
  const std::string text =
      "[WIF]\nVersion=1.1\n[WARP]\nThreads=4\nColor=2\n[THREADING]\n1=1\n2=2\n3=3\n4=4\n"
      "[WEAVING]\nShafts=4\nTreadles=6\n[WEFT]\n"
      "[TIEUP]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n6=1,2,3\n[TREADLING]\n1=1\n2=2\n3=3\n4=4\n"
      "[COLOR PALETTE]\nRange=0,255\nEntries=2\n[COLOR TABLE]\n1=255,0,0\n2=0,0,255\n"
      "[WARP COLORS]\n3=1\n";
  const WifDraft d = parse_quiet(text);
  EXPECT_TRUE(d.rising_shed);
  EXPECT_EQ(d.spec.matrix, twill(2, 2, false));
  EXPECT_TRUE(has_warning(d, "[WEFT]: no Threads; using 4"));
  ASSERT_EQ(d.spec.end_colors.size(), 4u);
  EXPECT_EQ(d.spec.end_colors[0], (Rgb{0, 0, 1}));
  EXPECT_EQ(d.spec.end_colors[2], (Rgb{1, 0, 0}));
  EXPECT_EQ(d.spec.end_colors[3], (Rgb{0, 0, 1}));
  EXPECT_TRUE(d.spec.pick_colors.empty());
  // No Spacing/Thickness: the YarnGeometry defaults.
  EXPECT_EQ(d.spec.warp.spacing_mm, YarnGeometry{}.spacing_mm);
  EXPECT_TRUE(d.spec.end_geometry.empty());
  // Missing Shafts and Treadles are inferred from the highest used, with a warning.
  const WifDraft inferred = parse_quiet(
      "[WIF]\nVersion=1.1\n[WARP]\nThreads=4\n[THREADING]\n1=1\n2=2\n3=3\n4=4\n[WEFT]\nThreads=4\n"
      "[TIEUP]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n[TREADLING]\n1=1\n2=2\n3=3\n4=4\n");
  EXPECT_EQ(inferred.shafts, 4);
  EXPECT_EQ(inferred.treadles, 4);
  EXPECT_TRUE(has_warning(inferred, "no Shafts; using 4"));
  EXPECT_EQ(inferred.spec.matrix, twill(2, 2, false));
}

TEST(Wif, RowsAreOneBasedInAnyOrderWithComments) {
  const std::string shuffled =
      "; leading comment\n[wif]\nversion=1.1\n[Warp]\nthreads=4\n"
      "[threading]\n4=4 ; the last end\n2=2\n\n   ; indented comment\n1=1\n3=3\n"
      "[Weaving]\nSHAFTS=4\ntreadles=4\n[weft]\nTHREADS=4\n"
      "[Tie-Up]\n3 = 3, 4\n1=1,2\n4=4,1\n2=2,3\n[treadling]\n2=2\n4=4\n1=1\n3=3\n";
  EXPECT_EQ(parse_quiet(shuffled).spec.matrix, twill(2, 2, false));
  expect_wif_error([] { parse_quiet(draft(kTwillLiftplan + "0=1\n")); },
                   {"test.wif", "[LIFTPLAN] line", "'0' is not a WEFT thread number"});
  expect_wif_error([] { parse_quiet(draft(kTwillLiftplan + "5=1\n")); },
                   {"[LIFTPLAN] line", "WEFT thread 5 is beyond [WEFT] Threads=4"});
  // The line number counts every line of the file, comments and blanks included.
  expect_wif_error(
      [] {
        parse_quiet(
            "[WIF]\n; c\n\n[WARP]\nThreads=2\n[THREADING]\n1=1\nx=2\n[LIFTPLAN]\n1=1\n2=2\n");
      },
      {"[THREADING] line 8", "'x'"});
}

TEST(Wif, MultiShaftThreadingRisesWithEitherShaft) {
  const std::string text =
      "[WIF]\nVersion=1.1\n[WEAVING]\nShafts=3\nTreadles=3\n[WARP]\nThreads=3\n[WEFT]\nThreads=3\n"
      "[THREADING]\n1=1\n2=2\n3=1,3\n[LIFTPLAN]\n1=1\n2=2\n3=3\n";
  const WifDraft d = parse_quiet(text);
  EXPECT_EQ(d.spec.matrix, matrix_from_rows({"101", "010", "001"}, "expected"));
  EXPECT_EQ(d.threading[2], (std::vector<int>{0, 2}));
  // Sinking shed: an end goes down if any of its shafts sinks.
  std::string sinking = text;
  sinking.replace(sinking.find("Treadles=3\n"), 11, "Treadles=3\nRising Shed=no\n");
  EXPECT_EQ(parse_quiet(sinking).spec.matrix, d.spec.matrix.complement());
}

TEST(Wif, PrivateAndUnknownSectionsAreSkippedWithAWarning) {
  const std::string text = draft(
      "[PRIVATE PIXELOOM SETTINGS]\nZoom=3\nnot a key line\n[FANCY EXTENSION]\n???\n"
      "[NOTES]\n1=just notes\n[CONTENTS]\nTHREADING=true\n" +
      kTwillLiftplan);
  const WifDraft d = parse_quiet(text);
  EXPECT_EQ(d.spec.matrix, twill(2, 2, false));
  EXPECT_TRUE(has_warning(d, "skipping private section [PRIVATE PIXELOOM SETTINGS]"));
  EXPECT_TRUE(has_warning(d, "skipping unknown section [FANCY EXTENSION]"));
  EXPECT_FALSE(has_warning(d, "NOTES"));
  EXPECT_FALSE(has_warning(d, "CONTENTS"));
}

TEST(Wif, ColoursAreScaledByThePaletteRangeAndLinearised) {
  const std::string text = draft(kTwillLiftplan +
                                     "[COLOR PALETTE]\nEntries=3\nRange=0,999\n"
                                     "[COLOR TABLE]\n1=999,0,0\n2=500,250,999\n3=0,0,0\n"
                                     "[WEFT]\nColor=2\n[WEFT COLORS]\n4=1,999,0,0\n",
                                 "[WARP]\nThreads=4\nColor=3,0,0,0\n");
  const WifDraft d = parse_quiet(text);
  ASSERT_EQ(d.spec.pick_colors.size(), 4u);
  EXPECT_NEAR(d.spec.pick_colors[0][0], srgb_to_linear(500.0 / 999.0), 1e-12);
  EXPECT_NEAR(d.spec.pick_colors[0][1], srgb_to_linear(250.0 / 999.0), 1e-12);
  EXPECT_NEAR(d.spec.pick_colors[0][2], 1.0, 1e-12);
  EXPECT_EQ(d.spec.pick_colors[3], (Rgb{1, 0, 0}));  // "index,R,G,B": the index counts
  ASSERT_EQ(d.spec.end_colors.size(), 4u);
  EXPECT_EQ(d.spec.end_colors[1], (Rgb{0, 0, 0}));
  // A lone Range value is the maximum; a minimum shifts the scale.
  const WifDraft offset = parse_quiet(draft(kTwillLiftplan + "[COLOR PALETTE]\nRange=100,200\n"
                                                             "[COLOR TABLE]\n1=150,100,200\n",
                                            "[WARP]\nThreads=4\nColor=1\n"));
  EXPECT_NEAR(offset.spec.end_colors[0][0], srgb_to_linear(0.5), 1e-12);
  EXPECT_EQ(offset.spec.end_colors[0][1], 0.0);
  EXPECT_EQ(offset.spec.end_colors[0][2], 1.0);
  const WifDraft lone =
      parse_quiet(draft(kTwillLiftplan + "[COLOR PALETTE]\nRange=999\n[COLOR TABLE]\n1=999,0,0\n",
                        "[WARP]\nThreads=4\nColor=1\n"));
  EXPECT_EQ(lone.spec.end_colors[0], (Rgb{1, 0, 0}));
  // Out of range: clamped with a warning naming the line.
  const WifDraft clamped = parse_quiet(draft(kTwillLiftplan + "[COLOR PALETTE]\nRange=0,255\n"
                                                              "[COLOR TABLE]\n1=300,0,0\n",
                                             "[WARP]\nThreads=4\nColor=1\n"));
  EXPECT_EQ(clamped.spec.end_colors[0][0], 1.0);
  EXPECT_TRUE(has_warning(clamped, "[COLOR TABLE] line"));
  // A colour that is not in the table is an error at the referring line.
  expect_wif_error(
      [] { parse_quiet(draft(kTwillLiftplan + "[COLOR TABLE]\n1=1,2,3\n[WEFT COLORS]\n2=7\n")); },
      {"[WEFT COLORS] line", "colour 7 is not in the [COLOR TABLE]"});
}

TEST(Wif, UnitsSpacingAndThicknessBecomeYarnGeometry) {
  const std::string text = draft(kTwillLiftplan +
                                     "[WEFT]\nUnits=Decipoints\nSpacing=36\nThickness=18\n"
                                     "[WARP SPACING]\n2=0.2\n[WARP THICKNESS]\n3=0.05\n",
                                 "[WARP]\nThreads=4\nUnits=centimeters\nSpacing=0.1\n"
                                 "Thickness=0.12\n");
  const WifDraft d = parse_quiet(text);
  // Warp: 1 mm spacing, 1.2 mm thick -> full width (clamped), flattened to half its thickness.
  EXPECT_NEAR(d.spec.warp.spacing_mm, 1.0, 1e-12);
  EXPECT_EQ(d.spec.warp.width, 1.0);
  EXPECT_NEAR(d.spec.warp.height_mm, 0.6, 1e-12);
  // Weft: 36 decipoints = 0.05 inch = 1.27 mm; 18 decipoints thick = half the spacing.
  EXPECT_NEAR(d.spec.weft.spacing_mm, 1.27, 1e-12);
  EXPECT_NEAR(d.spec.weft.width, 0.5, 1e-12);
  EXPECT_NEAR(d.spec.weft.height_mm, 0.3175, 1e-12);
  // Per-end overrides: end 2 in a 2 mm space, end 3 0.5 mm thick.
  ASSERT_EQ(d.spec.end_geometry.size(), 4u);
  EXPECT_NEAR(d.spec.end_geometry[1].spacing_mm, 2.0, 1e-12);
  EXPECT_NEAR(d.spec.end_geometry[1].width, 0.6, 1e-12);
  EXPECT_NEAR(d.spec.end_geometry[2].width, 0.5, 1e-12);
  EXPECT_NEAR(d.spec.end_geometry[2].height_mm, 0.25, 1e-12);
  EXPECT_NEAR(weave_tile_size(d.spec).width_mm, 5.0, 1e-12);
  EXPECT_TRUE(d.spec.pick_geometry.empty());
  expect_wif_error(
      [&] { parse_quiet(draft(kTwillLiftplan, "[WARP]\nThreads=4\nUnits=furlongs\n")); },
      {"[WARP] line", "furlongs"});
  expect_wif_error([&] { parse_quiet(draft(kTwillLiftplan, "[WARP]\nThreads=4\nSpacing=-1\n")); },
                   {"[WARP] line", "negative"});
  const WifDraft no_units = parse_quiet(draft(kTwillLiftplan, "[WARP]\nThreads=4\nSpacing=0.05\n"));
  EXPECT_TRUE(has_warning(no_units, "no Units"));
  EXPECT_NEAR(no_units.spec.warp.spacing_mm, 1.27, 1e-12);
}

TEST(Wif, ExampleDraftsGiveTheirNamedWeaves) {
  set_quiet(true);
  const WifDraft twill_draft = read_wif(kExamples + "twill-2-2.wif");
  EXPECT_EQ(twill_draft.title, "2/2 twill, navy and natural");
  EXPECT_EQ(twill_draft.spec.matrix.ends, 8);
  EXPECT_EQ(twill_draft.spec.matrix.picks, 4);
  for (int p = 0; p < 4; ++p)
    for (int e = 0; e < 8; ++e)
      EXPECT_EQ(twill_draft.spec.matrix.warp_up(p, e), twill(2, 2, false).warp_up(p, e % 4));
  EXPECT_NEAR(twill_draft.spec.warp.spacing_mm, 1.27, 1e-12);
  EXPECT_EQ(twill_draft.spec.end_colors[3], twill_draft.spec.end_colors[7]);
  EXPECT_NE(twill_draft.spec.end_colors[0], twill_draft.spec.end_colors[3]);
  EXPECT_TRUE(twill_draft.warnings.empty());

  const WifDraft satin5 = read_wif(kExamples + "satin-5-liftplan.wif");
  EXPECT_TRUE(satin5.from_liftplan);
  EXPECT_EQ(satin5.spec.matrix, named_weave("satin5"));

  const WifDraft crowfoot = read_wif(kExamples + "crowfoot-satin-4-liftplan.wif");
  EXPECT_EQ(crowfoot.spec.matrix, matrix_from_rows({"0111", "1101", "1011", "1110"}, "crowfoot"));
  EXPECT_NEAR(crowfoot.spec.end_colors[0][0], srgb_to_linear(870.0 / 999.0), 1e-12);

  const WifDraft diamond = read_wif(kExamples + "diamond-point-twill.wif");
  const WeaveMatrix& m = diamond.spec.matrix;
  ASSERT_EQ(m.ends, 6);
  ASSERT_EQ(m.picks, 6);
  // Brute force from the draft: end e on shaft T[e], pick p presses treadle T[p], treadle t lifts
  // shafts t and t % 4 + 1. Point threading and treadling mirror the repeat in both directions.
  const int point[6] = {1, 2, 3, 4, 3, 2};
  for (int p = 0; p < 6; ++p)
    for (int e = 0; e < 6; ++e) {
      const bool up = point[e] == point[p] || point[e] == point[p] % 4 + 1;
      EXPECT_EQ(m.warp_up(p, e), up) << p << "," << e;
      EXPECT_EQ(m.warp_up(p, e), m.warp_up(p, (6 - e) % 6));
      EXPECT_EQ(m.warp_up(p, e), m.warp_up((6 - p) % 6, e));
    }
  EXPECT_EQ(diamond.spec.pick_colors[1], diamond.spec.pick_colors[3]);
  // Every example makes valid maps.
  for (const WifDraft* d : {&twill_draft, &satin5, &crowfoot, &diamond}) {
    const FabricMaps maps = generate_weave_maps(d->spec, 32);
    EXPECT_EQ(maps.texel_count(), 32u * 32u);
  }
  set_quiet(false);
}

TEST(Wif, UnweavableAndMalformedDraftsNameSectionAndLine) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> files = {
      {"broken-shaft-beyond-count.wif",
       {"broken-shaft-beyond-count.wif: [THREADING] line 20",
        "shaft 5 is beyond [WEAVING] Shafts=4"}},
      {"broken-unthreaded-end.wif", {"[THREADING]", "end 4 is not threaded"}},
      {"broken-pick-never-interlaces.wif", {"[TREADLING] line 30", "pick 3", "never interlaces"}},
      {"broken-no-threading.wif", {"broken-no-threading.wif", "no [THREADING]"}},
      {"broken-treadle-beyond-count.wif",
       {"[TREADLING] line 25", "treadle 3 is beyond [WEAVING] Treadles=2"}},
      {"broken-zero-threads.wif", {"[WEFT] line 13", "Threads=0"}},
  };
  for (const auto& [file, fragments] : files) {
    SCOPED_TRACE(file);
    const std::string path = kData + file;
    set_quiet(true);
    try {
      read_wif(path);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Input);
      for (const std::string& f : fragments)
        EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what() << " / " << f;
    }
    set_quiet(false);
  }
  const std::vector<std::pair<std::string, std::vector<std::string>>> inline_cases = {
      {"[WARP]\nThreads=4\n[THREADING]\n1=1\n", {"no [WIF] section"}},
      {draft(kTwillLiftplan + "[WEAVING\n"), {"malformed section header"}},
      {draft(kTwillLiftplan + "[TEXT]\nTitle=x\n[LIFTPLAN]\njust words\n"),
       {"[LIFTPLAN] line", "expected Key=Value"}},
      {draft("[WEAVING]\nShafts=4\n[WEFT]\nThreads=4\n"),
       {"neither a [TREADLING] nor a [LIFTPLAN]"}},
      {draft("[WEAVING]\nShafts=4\n[WEFT]\nThreads=4\n[TREADLING]\n1=1\n"), {"needs a [TIEUP]"}},
      {draft(kTwillLiftplan + "[LIFTPLAN]\n2=2,x\n"), {"[LIFTPLAN] line", "'2,x'"}},
      {draft(kTwillLiftplan + "[LIFTPLAN]\n2=9\n"), {"[LIFTPLAN] line", "shaft 9 is beyond"}},
      {draft("[WEAVING]\nShafts=4\nRising Shed=maybe\n[WEFT]\nThreads=4\n[LIFTPLAN]\n1=1\n"),
       {"[WEAVING] line", "'maybe' is not a boolean"}},
      {draft("[WEAVING]\nShafts=four\n[WEFT]\nThreads=4\n[LIFTPLAN]\n1=1\n"),
       {"[WEAVING] line", "Shafts = 'four'"}},
      {draft("[WEAVING]\nShafts=4\nTreadles=2\n[WEFT]\nThreads=2\n[TIEUP]\n1=1,5\n"
             "[TREADLING]\n1=1\n2=2\n"),
       {"[TIEUP] line", "shaft 5 is beyond"}},
      {draft(kTwillLiftplan, "[WARP]\nThreads=9000\n"), {"[WARP] line", "outside 0..4096"}},
      {draft("[WEAVING]\nShafts=4\n[WEFT]\nThreads=3\n[LIFTPLAN]\n1=1,2,3,4\n2=1,2\n3=3,4\n"),
       {"[LIFTPLAN] line", "pick 1", "never interlaces"}},
      {draft("[WEAVING]\nShafts=4\n[WEFT]\nThreads=3\n[LIFTPLAN]\n1=1,2\n2=3,4\n"),
       {"[LIFTPLAN]", "pick 3 has no entry"}},
      {draft("[WEAVING]\nShafts=4\n[WEFT]\nThreads=2\n[LIFTPLAN]\n1=1,3\n2=1,3\n"),
       {"[THREADING] line", "end 1 (shafts 1) never interlaces"}},
  };
  for (const auto& [text, fragments] : inline_cases) {
    SCOPED_TRACE(text);
    set_quiet(true);
    try {
      parse_wif(text, "inline.wif");
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::Input);
      EXPECT_NE(std::string(e.what()).find("inline.wif"), std::string::npos) << e.what();
      for (const std::string& f : fragments)
        EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what() << " / " << f;
    }
    set_quiet(false);
  }
  expect_wif_error([] { read_wif(kData + "does-not-exist.wif"); },
                   {"does-not-exist.wif", "cannot open"});
}

TEST(Wif, TieUpEntriesBeyondTheTreadleCountAreIgnored) {
  // Drafting programs write tie-up rows for treadles the treadling never uses.
  const WifDraft d =
      parse_quiet(draft("[WEAVING]\nShafts=4\nTreadles=4\n[WEFT]\nThreads=4\n"
                        "[TIEUP]\n1=1,2\n2=2,3\n3=3,4\n4=4,1\n5=1,3\n6=2,4\n"
                        "[TREADLING]\n1=1\n2=2\n3=3\n4=4\n"));
  EXPECT_EQ(d.spec.matrix, twill(2, 2, false));
  EXPECT_TRUE(has_warning(d, "treadle 5 is beyond [WEAVING] Treadles=4"));
  // Duplicate keys: the later value wins, with a warning naming both lines.
  const WifDraft dup = parse_quiet(draft(kTwillLiftplan + "[LIFTPLAN]\n1=1,2\n"));
  EXPECT_TRUE(has_warning(dup, "repeats line"));
  EXPECT_TRUE(has_warning(dup, "appears again"));
}

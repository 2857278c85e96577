// Weave matrices: each named weave against its textile definition, parsing and weavability.
#include <gtest/gtest.h>

#include <numeric>
#include <string>

#include "bake/inputs/weave.hpp"
#include "common/error.hpp"

using namespace clothbake;
using namespace clothbake::weave;

namespace {

// Expects `fn` to throw Error(Input) whose message contains every fragment.
template <class Fn>
void expect_input_error(Fn&& fn, std::initializer_list<std::string> fragments) {
  try {
    fn();
    ADD_FAILURE() << "no error thrown";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input) << e.what();
    for (const std::string& f : fragments)
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
          << "message '" << e.what() << "' lacks '" << f << "'";
  }
}

int count_up_in_pick(const WeaveMatrix& m, int p) {
  int n = 0;
  for (int e = 0; e < m.ends; ++e)
    n += m.warp_up(p, e);
  return n;
}

}  // namespace

TEST(WeaveMatrix, PlainWeaveIsACheckerboard) {
  const WeaveMatrix m = plain_weave();
  ASSERT_EQ(m.picks, 2);
  ASSERT_EQ(m.ends, 2);
  for (int p = 0; p < 2; ++p)
    for (int e = 0; e < 2; ++e)
      EXPECT_EQ(m.warp_up(p, e), (p + e) % 2 == 0);
  EXPECT_EQ(named_weave("plain"), m);
  EXPECT_EQ(named_weave(" Tabby "), m);
}

TEST(WeaveMatrix, TwillDiagonalShiftsByOneEndPerPick) {
  for (int over = 1; over <= 4; ++over) {
    for (int under = 1; under <= 4; ++under) {
      for (bool left : {false, true}) {
        const WeaveMatrix m = twill(over, under, left);
        const int n = over + under;
        ASSERT_EQ(m.picks, n);
        ASSERT_EQ(m.ends, n);
        // Pick 0: warp up on ends 0 .. over-1 (definition).
        for (int e = 0; e < n; ++e)
          EXPECT_EQ(m.warp_up(0, e), e < over);
        // Each pick is the previous one shifted by one end: right (+1) or left (-1).
        const int step = left ? -1 : 1;
        for (int p = 1; p < n; ++p)
          for (int e = 0; e < n; ++e)
            EXPECT_EQ(m.warp_up(p, e), m.warp_up_wrapped(p - 1, e - step))
                << over << "/" << under << (left ? " left" : " right") << " p" << p << " e" << e;
        // Along every end the warp floats over exactly `over` picks.
        for (int e = 0; e < n; ++e) {
          int up = 0;
          for (int p = 0; p < n; ++p)
            up += m.warp_up(p, e);
          EXPECT_EQ(up, over);
        }
        EXPECT_NO_THROW(check_weavable(m, "twill"));
      }
    }
  }
  EXPECT_EQ(named_weave("twill2/1"), twill(2, 1, false));
  EXPECT_EQ(named_weave("twill3/1-left"), twill(3, 1, true));
  EXPECT_EQ(named_weave("TWILL2/2-Right"), twill(2, 2, false));
  // Left- and right-hand twills are mirror images: reversing the ends of one gives the other
  // up to a shift.
  const WeaveMatrix r = twill(3, 1, false), l = twill(3, 1, true);
  bool mirror_found = false;
  for (int shift = 0; shift < 4 && !mirror_found; ++shift) {
    bool same = true;
    for (int p = 0; p < 4; ++p)
      for (int e = 0; e < 4; ++e)
        same &= r.warp_up(p, e) == l.warp_up_wrapped(p, shift - e);
    mirror_found = same;
  }
  EXPECT_TRUE(mirror_found);
  EXPECT_NE(r, l);
}

TEST(WeaveMatrix, SatinInterlacingsAreNeverAdjacent) {
  for (int n = 5; n <= 16; ++n) {
    for (int move = 2; move < n - 1; ++move) {
      if (n == 6) {
        expect_input_error([&] { satin(n, move); }, {"satin6", "irregular"});
        continue;
      }
      if (std::gcd(n, move) != 1) {
        expect_input_error([&] { satin(n, move); }, {"move " + std::to_string(move)});
        continue;
      }
      const WeaveMatrix m = satin(n, move);
      // Exactly one interlacing (weft on top) per pick and per end.
      for (int p = 0; p < n; ++p)
        EXPECT_EQ(count_up_in_pick(m, p), n - 1);
      for (int e = 0; e < n; ++e) {
        int down = 0;
        for (int p = 0; p < n; ++p)
          down += !m.warp_up(p, e);
        EXPECT_EQ(down, 1);
      }
      // No two interlacings touch, not even diagonally (periodically).
      for (int p = 0; p < n; ++p)
        for (int e = 0; e < n; ++e) {
          if (m.warp_up(p, e)) continue;
          for (int dp = -1; dp <= 1; ++dp)
            for (int de = -1; de <= 1; ++de)
              if (dp != 0 || de != 0) {
                EXPECT_TRUE(m.warp_up_wrapped(p + dp, e + de))
                    << "satin" << n << "-" << move << " touching at " << p << "," << e;
              }
        }
      // Interlacing on pick p at end p * move mod n (definition).
      for (int p = 0; p < n; ++p)
        EXPECT_FALSE(m.warp_up(p, (p * move) % n));
      EXPECT_EQ(sateen(n, move), m.complement());
    }
  }
  EXPECT_EQ(named_weave("satin5"), satin(5, 2));
  EXPECT_EQ(named_weave("satin8-3"), satin(8, 3));
  EXPECT_EQ(named_weave("sateen8-5"), satin(8, 5).complement());
  EXPECT_EQ(default_satin_move(8), 3);
  EXPECT_EQ(default_satin_move(7), 2);
  expect_input_error([] { satin(4, 1); }, {"satin4", "irregular"});
  expect_input_error([] { satin(6, 5); }, {"satin6"});
  expect_input_error([] { named_weave("satin8-2"); }, {"move 2", "valid moves: 3, 5"});
  expect_input_error([] { named_weave("satin6"); }, {"satin6"});
}

TEST(WeaveMatrix, BasketIsPlainWeaveWithDoubledThreads) {
  for (int n = 1; n <= 4; ++n) {
    const WeaveMatrix m = basket(n);
    ASSERT_EQ(m.picks, 2 * n);
    ASSERT_EQ(m.ends, 2 * n);
    for (int p = 0; p < 2 * n; ++p)
      for (int e = 0; e < 2 * n; ++e)
        EXPECT_EQ(m.warp_up(p, e), plain_weave().warp_up(p / n, e / n));
    // n x n blocks are uniform.
    for (int p = 0; p < 2 * n; p += n)
      for (int e = 0; e < 2 * n; e += n)
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j)
            EXPECT_EQ(m.warp_up(p + i, e + j), m.warp_up(p, e));
  }
  EXPECT_EQ(named_weave("basket2"), basket(2));
  EXPECT_EQ(named_weave("hopsack3"), basket(3));
  EXPECT_EQ(basket(1), plain_weave());
}

TEST(WeaveMatrix, UnknownNamesListTheValidForms) {
  for (const char* bad : {"satinx", "twill", "twill2", "twill2/1-up", "basket", "weird", "",
                          "plain2", "satin5-", "basket2x"})
    expect_input_error([&] { named_weave(bad); }, {"valid forms", "twill<over>/<under>"});
  expect_input_error([] { named_weave("twill2/0"); }, {"twill 2/0"});
  expect_input_error([] { named_weave("twill0/3"); }, {"twill 0/3"});
  expect_input_error([] { named_weave("basket0"); }, {"basket0"});
}

TEST(WeaveMatrix, RowsRoundTripAndBadCellsAreLocated) {
  const WeaveMatrix m =
      matrix_from_rows({"1100", "0110", "0011", "1001"}, "f.toml: [weave] matrix");
  EXPECT_EQ(m, twill(2, 2, false));
  EXPECT_EQ(matrix_from_rows(m.to_rows(), "x"), m);
  EXPECT_EQ(matrix_from_rows({"11 00", "01|10", "0_011", "1 0 0 1"}, "x"), m);
  expect_input_error(
      [] {
        matrix_from_rows({"1100", "01x0"}, "f.toml: [weave] matrix");
      },
      {"f.toml: [weave] matrix", "row 2, column 3", "'x'"});
  expect_input_error([] { matrix_from_rows({"1100", "010"}, "f.toml"); }, {"row 2 has 3 cells"});
  expect_input_error([] { matrix_from_rows({}, "f.toml"); }, {"f.toml", "no rows"});
  expect_input_error([] { matrix_from_rows({"10", " "}, "f.toml"); }, {"row 2 is empty"});
}

TEST(WeaveMatrix, UnweavableThreadsAreNamed) {
  // End 3 is always down: the warp thread floats under every pick.
  expect_input_error(
      [] {
        check_weavable(matrix_from_rows({"1000", "0100"}, "m"), "fabric.toml");
      },
      {"fabric.toml", "end 3", "never interlaces"});
  // Pick 2 is all warp-up: the weft thread is never on top.
  expect_input_error([] { check_weavable(matrix_from_rows({"10", "11"}, "m"), "w"); }, {"end 1"});
  expect_input_error(
      [] {
        check_weavable(matrix_from_rows({"10", "11", "01"}, "m"), "w");
      },
      {"pick 2"});
  WeaveMatrix broken = plain_weave();
  broken.cells.pop_back();
  expect_input_error([&] { check_weavable(broken, "w"); }, {"inconsistent"});
  EXPECT_NO_THROW(check_weavable(satin(5, 2), "w"));
}

TEST(WeaveMatrix, ComplementRollAndFloats) {
  const WeaveMatrix m = twill(3, 1, false);
  EXPECT_EQ(m.complement().complement(), m);
  EXPECT_EQ(m.complement(), twill(1, 3, false).rolled(0, 3));
  EXPECT_EQ(m.rolled(1, 0), m.rolled(0, -1));  // right-hand twill: a pick shift is an end shift
  EXPECT_EQ(m.rolled(4, 4), m);
  FloatLengths f = float_lengths(m);
  EXPECT_EQ(f.longest_warp_float, 3);
  EXPECT_EQ(f.longest_weft_float, 1);
  f = float_lengths(satin(8, 3));
  EXPECT_EQ(f.longest_warp_float, 7);
  EXPECT_EQ(f.longest_weft_float, 1);
  f = float_lengths(basket(2));
  EXPECT_EQ(f.longest_warp_float, 2);
  EXPECT_EQ(f.longest_weft_float, 2);
  expect_input_error([] { make_matrix(0, 3); }, {"0 picks"});
  expect_input_error([] { make_matrix(2, kMaxRepeat + 1); }, {"ends"});
}

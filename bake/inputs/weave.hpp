// Weave matrices: which thread is on top at each crossing of one repeat of a woven fabric.
//
// A WeaveMatrix is the "drawdown" of a weave: rows are picks (weft threads, laid along x), columns
// are ends (warp threads, running along y); cell (pick, end) is 1 when the warp end is on top of
// the pick at their crossing. The matrix is one repeat: it tiles periodically in both directions.
// Named weaves follow the usual textile definitions (docs/weaves.md): plain, twill N/M (right- or
// left-hand), N-shaft satin with a move number, and N x N basket (hopsack).
//
// Everything here is safe on untrusted input: bad names or cells throw clothbake::Error with
// ExitCode::Input and a message naming the source; nothing aborts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace clothbake::weave {

// Largest number of picks or ends accepted in a repeat (keeps cells and maps bounded).
inline constexpr int kMaxRepeat = 4096;

struct WeaveMatrix {  // rows = picks (weft threads), columns = ends (warp threads)
  int picks = 0, ends = 0;
  std::vector<uint8_t> cells;  // picks * ends, row-major; 1 = warp on top at (pick, end)

  // Precondition: 0 <= pick < picks, 0 <= end < ends.
  bool warp_up(int pick, int end) const {
    return cells[std::size_t(pick) * std::size_t(ends) + std::size_t(end)] != 0;
  }
  // Periodic access: any integer pick/end, wrapped into the repeat (requires a non-empty matrix).
  bool warp_up_wrapped(long pick, long end) const;
  void set(int pick, int end, bool warp_on_top) {
    cells[std::size_t(pick) * std::size_t(ends) + std::size_t(end)] = warp_on_top ? 1 : 0;
  }
  // The weave seen from the back: every cell inverted (also the effect of a sinking shed).
  WeaveMatrix complement() const;
  // The matrix cyclically shifted: result(p, e) = this(p - pick_shift, e - end_shift) (wrapped).
  WeaveMatrix rolled(int pick_shift, int end_shift) const;
  // Rows of '0'/'1' characters, first row = first pick (the inverse of matrix_from_rows).
  std::vector<std::string> to_rows() const;

  bool operator==(const WeaveMatrix& other) const {
    return picks == other.picks && ends == other.ends && cells == other.cells;
  }
  bool operator!=(const WeaveMatrix& other) const { return !(*this == other); }
};

// An all-zero (all weft on top) matrix of the given size. Throws Error(Input) if a size is outside
// [1, kMaxRepeat]; `where` names the source in that message.
WeaveMatrix make_matrix(int picks, int ends, const std::string& where = "weave matrix");

// 2 x 2 plain (tabby) weave: warp up at (0,0) and (1,1).
WeaveMatrix plain_weave();
// Twill over/under: a repeat of over + under; on pick 0 the warp is up on ends 0 .. over-1; each
// following pick shifts the pattern by one end, to the right (+end) for a right-hand twill (the
// diagonal rises to the right, "Z" twill) or to the left for left_hand. Throws Error(Input) if over
// or under is < 1 or over + under > kMaxRepeat.
WeaveMatrix twill(int over, int under, bool left_hand = false);
// n-shaft satin, warp-faced: the warp floats over n-1 picks and each pick is held by a single
// interlacing where the weft is on top, at end (p * move) mod n on pick p. A regular satin needs
// 1 < move < n - 1 and gcd(n, move) == 1 (otherwise interlacings touch or repeat early), so n >= 5
// and n != 6. Throws Error(Input) naming the invalid n or move and listing the valid moves.
WeaveMatrix satin(int n, int move);
// The weft-faced counterpart (sateen): satin(n, move).complement().
WeaveMatrix sateen(int n, int move);
// The conventional move of an n-shaft satin: the smallest valid move (2 for 5, 3 for 8, 2 for 7).
// Throws Error(Input) if there is none (n < 5 or n == 6).
int default_satin_move(int n);
// n x n basket (hopsack): plain weave with every thread doubled n times; 2n x 2n repeat.
// Throws Error(Input) if n < 1 or 2n > kMaxRepeat.
WeaveMatrix basket(int n);

// Named weaves (case-insensitive, surrounding spaces ignored):
//   "plain" (also "tabby"), "twill<O>/<U>" with optional "-right" (default) or "-left",
//   "satin<N>" (default move) or "satin<N>-<M>" (move M), "sateen<N>[-<M>]" (weft-faced),
//   "basket<N>" (also "hopsack<N>").
// Examples: "plain", "twill2/1", "twill3/1-left", "twill2/2-right", "satin5", "satin8-3",
// "basket2". Throws Error(Input) naming the weave and listing the valid forms.
WeaveMatrix named_weave(const std::string& name);
// The list of valid name forms, for messages and --help texts.
std::string named_weave_forms();

// Rows of '0'/'1' characters (first row = first pick); spaces, tabs, '_' and '|' inside a row are
// ignored as visual separators. `where` names the source for messages, e.g.
// "fabric.toml: [weave] matrix". Throws Error(Input) naming the row and column (1-based) of a bad
// cell, an empty matrix, or a row whose length differs from the first row's.
WeaveMatrix matrix_from_rows(const std::vector<std::string>& rows, const std::string& where);

// Rejects what cannot be woven: an empty or inconsistent matrix, or an end or pick that never
// interlaces (a thread that floats over the whole repeat on one face and is not held). The message
// names `where` and the first such thread, 1-based ("end 3" / "pick 2"). Throws Error(Input).
void check_weavable(const WeaveMatrix& m, const std::string& where);

// Longest float (consecutive crossings on the same face, periodic) of any end and of any pick, in
// crossings; useful for warnings about loose weaves. Precondition: weavable matrix.
struct FloatLengths {
  int longest_warp_float = 0;  // along an end: consecutive picks with the warp on top
  int longest_weft_float = 0;  // along a pick: consecutive ends with the weft on top
};
FloatLengths float_lengths(const WeaveMatrix& m);

}  // namespace clothbake::weave

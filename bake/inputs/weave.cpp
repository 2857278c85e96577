// Weave matrices and the named weaves (docs/weaves.md, "Weave matrices").
#include "bake/inputs/weave.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <numeric>
#include <optional>

#include "common/error.hpp"
#include "model/tile.hpp"

namespace clothbake::weave {

namespace {

std::string lower_trimmed(const std::string& text) {
  std::size_t begin = 0, end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin])))
    ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1])))
    --end;
  std::string out = text.substr(begin, end - begin);
  for (char& c : out)
    c = char(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Parses a whole decimal integer in [1, 1'000'000] at text[pos...]; advances pos.
std::optional<int> take_int(const std::string& text, std::size_t& pos) {
  std::size_t start = pos;
  while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos])))
    ++pos;
  if (pos == start || pos - start > 7) return std::nullopt;
  int value = 0;
  std::from_chars(text.data() + start, text.data() + pos, value);
  return value;
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.size() >= prefix.size() && text.compare(0, prefix.size(), prefix) == 0;
}

std::string valid_satin_moves(int n) {
  std::string list;
  for (int m = 2; m < n - 1; ++m) {
    if (std::gcd(n, m) != 1) continue;
    if (!list.empty()) list += ", ";
    list += std::to_string(m);
  }
  return list.empty() ? "none" : list;
}

}  // namespace

bool WeaveMatrix::warp_up_wrapped(long pick, long end) const {
  return warp_up(int(model::wrap_index(pick, picks)), int(model::wrap_index(end, ends)));
}

WeaveMatrix WeaveMatrix::complement() const {
  WeaveMatrix out = *this;
  for (uint8_t& c : out.cells)
    c = c ? 0 : 1;
  return out;
}

WeaveMatrix WeaveMatrix::rolled(int pick_shift, int end_shift) const {
  WeaveMatrix out = *this;
  for (int p = 0; p < picks; ++p)
    for (int e = 0; e < ends; ++e)
      out.set(p, e, warp_up_wrapped(long(p) - pick_shift, long(e) - end_shift));
  return out;
}

std::vector<std::string> WeaveMatrix::to_rows() const {
  std::vector<std::string> rows(std::size_t(std::max(picks, 0)));
  for (int p = 0; p < picks; ++p) {
    rows[std::size_t(p)].reserve(std::size_t(ends));
    for (int e = 0; e < ends; ++e)
      rows[std::size_t(p)] += warp_up(p, e) ? '1' : '0';
  }
  return rows;
}

WeaveMatrix make_matrix(int picks, int ends, const std::string& where) {
  if (picks < 1 || picks > kMaxRepeat || ends < 1 || ends > kMaxRepeat)
    throw_input_error(where + ": a weave repeat of " + std::to_string(picks) + " picks x " +
                      std::to_string(ends) + " ends is outside 1.." + std::to_string(kMaxRepeat));
  WeaveMatrix m;
  m.picks = picks;
  m.ends = ends;
  m.cells.assign(std::size_t(picks) * std::size_t(ends), 0);
  return m;
}

WeaveMatrix plain_weave() {
  return twill(1, 1);
}

WeaveMatrix twill(int over, int under, bool left_hand) {
  if (over < 1 || under < 1 || over > kMaxRepeat || under > kMaxRepeat - over)
    throw_input_error(
        "twill " + std::to_string(over) + "/" + std::to_string(under) +
        ": over and under must be >= 1 with over + under <= " + std::to_string(kMaxRepeat));
  const int n = over + under;
  WeaveMatrix m = make_matrix(n, n, "twill");
  for (int p = 0; p < n; ++p) {
    const int shift = left_hand ? -p : p;
    for (int k = 0; k < over; ++k)
      m.set(p, int(model::wrap_index(long(k) + shift, n)), true);
  }
  return m;
}

WeaveMatrix satin(int n, int move) {
  if (n < 5 || n == 6 || n > kMaxRepeat)
    throw_input_error("satin" + std::to_string(n) +
                      ": a regular satin needs 5 or more shafts and not 6 (4- and 6-shaft "
                      "'satins' are irregular: write them as a matrix or a WIF lift plan)");
  if (move <= 1 || move >= n - 1 || std::gcd(n, move) != 1)
    throw_input_error("satin" + std::to_string(n) + "-" + std::to_string(move) + ": move " +
                      std::to_string(move) + " is not valid for " + std::to_string(n) +
                      " shafts (valid moves: " + valid_satin_moves(n) + ")");
  WeaveMatrix m = make_matrix(n, n, "satin");
  std::fill(m.cells.begin(), m.cells.end(), uint8_t(1));
  for (int p = 0; p < n; ++p)
    m.set(p, int((long(p) * move) % n), false);
  return m;
}

WeaveMatrix sateen(int n, int move) {
  return satin(n, move).complement();
}

int default_satin_move(int n) {
  for (int m = 2; m < n - 1; ++m)
    if (std::gcd(n, m) == 1) return m;
  throw_input_error("satin" + std::to_string(n) +
                    ": no regular satin exists for this number of shafts (needs 5 or more, "
                    "and not 6)");
}

WeaveMatrix basket(int n) {
  if (n < 1 || n > kMaxRepeat / 2)
    throw_input_error("basket" + std::to_string(n) + ": n must be in 1.." +
                      std::to_string(kMaxRepeat / 2));
  WeaveMatrix m = make_matrix(2 * n, 2 * n, "basket");
  for (int p = 0; p < 2 * n; ++p)
    for (int e = 0; e < 2 * n; ++e)
      m.set(p, e, (p / n) == (e / n));
  return m;
}

std::string named_weave_forms() {
  return "plain (or tabby), twill<over>/<under>[-right|-left] (e.g. twill2/1, twill3/1-left), "
         "satin<n>[-<move>] (warp-faced, e.g. satin5, satin8-3), sateen<n>[-<move>] "
         "(weft-faced), basket<n> (or hopsack<n>, e.g. basket2)";
}

WeaveMatrix named_weave(const std::string& name) {
  const std::string key = lower_trimmed(name);
  auto fail = [&](const std::string& why) -> WeaveMatrix {
    throw_input_error("unknown weave '" + name + "'" + (why.empty() ? "" : " (" + why + ")") +
                      "; valid forms: " + named_weave_forms());
  };
  if (key == "plain" || key == "tabby") return plain_weave();
  std::size_t pos = 0;
  if (starts_with(key, "twill")) {
    pos = 5;
    auto over = take_int(key, pos);
    if (!over || pos >= key.size() || key[pos] != '/') return fail("expected twill<over>/<under>");
    ++pos;
    auto under = take_int(key, pos);
    if (!under) return fail("expected twill<over>/<under>");
    const std::string hand = key.substr(pos);
    if (hand.empty() || hand == "-right" || hand == "-r") return twill(*over, *under, false);
    if (hand == "-left" || hand == "-l") return twill(*over, *under, true);
    return fail("twill hand must be -right or -left");
  }
  const bool is_sateen = starts_with(key, "sateen");
  if (is_sateen || starts_with(key, "satin")) {
    pos = is_sateen ? 6 : 5;
    auto n = take_int(key, pos);
    if (!n) return fail("expected satin<n> or satin<n>-<move>");
    int move = 0;
    if (pos == key.size()) {
      move = default_satin_move(*n);
    } else {
      if (key[pos] != '-') return fail("expected satin<n> or satin<n>-<move>");
      ++pos;
      auto m = take_int(key, pos);
      if (!m || pos != key.size()) return fail("expected satin<n>-<move>");
      move = *m;
    }
    return is_sateen ? sateen(*n, move) : satin(*n, move);
  }
  for (const char* prefix : {"basket", "hopsack"}) {
    if (!starts_with(key, prefix)) continue;
    pos = std::string(prefix).size();
    auto n = take_int(key, pos);
    if (!n || pos != key.size()) return fail("expected basket<n>");
    return basket(*n);
  }
  return fail("");
}

WeaveMatrix matrix_from_rows(const std::vector<std::string>& rows, const std::string& where) {
  if (rows.empty()) throw_input_error(where + ": the weave matrix has no rows");
  if (rows.size() > std::size_t(kMaxRepeat))
    throw_input_error(where + ": the weave matrix has " + std::to_string(rows.size()) +
                      " rows, more than " + std::to_string(kMaxRepeat));
  std::vector<std::vector<uint8_t>> cells(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const std::string& row = rows[r];
    for (std::size_t i = 0; i < row.size(); ++i) {
      const char c = row[i];
      if (c == ' ' || c == '\t' || c == '_' || c == '|') continue;
      if (c != '0' && c != '1')
        throw_input_error(where + ": row " + std::to_string(r + 1) + ", column " +
                          std::to_string(cells[r].size() + 1) + " (character " +
                          std::to_string(i + 1) + "): '" + std::string(1, c) +
                          "' is not 0 or 1 (1 = warp on top)");
      if (cells[r].size() >= std::size_t(kMaxRepeat))
        throw_input_error(where + ": row " + std::to_string(r + 1) + " has more than " +
                          std::to_string(kMaxRepeat) + " cells");
      cells[r].push_back(c == '1' ? 1 : 0);
    }
    if (cells[r].empty()) throw_input_error(where + ": row " + std::to_string(r + 1) + " is empty");
    if (cells[r].size() != cells[0].size())
      throw_input_error(where + ": row " + std::to_string(r + 1) + " has " +
                        std::to_string(cells[r].size()) + " cells, but row 1 has " +
                        std::to_string(cells[0].size()));
  }
  WeaveMatrix m = make_matrix(int(rows.size()), int(cells[0].size()), where);
  for (int p = 0; p < m.picks; ++p)
    for (int e = 0; e < m.ends; ++e)
      m.set(p, e, cells[std::size_t(p)][std::size_t(e)] != 0);
  return m;
}

void check_weavable(const WeaveMatrix& m, const std::string& where) {
  if (m.picks < 1 || m.ends < 1 || m.picks > kMaxRepeat || m.ends > kMaxRepeat ||
      m.cells.size() != std::size_t(m.picks) * std::size_t(m.ends))
    throw_input_error(where + ": the weave matrix is empty or inconsistent (" +
                      std::to_string(m.picks) + " picks x " + std::to_string(m.ends) + " ends, " +
                      std::to_string(m.cells.size()) + " cells)");
  for (int e = 0; e < m.ends; ++e) {
    int up = 0;
    for (int p = 0; p < m.picks; ++p)
      up += m.warp_up(p, e) ? 1 : 0;
    if (up == 0 || up == m.picks)
      throw_input_error(where + ": end " + std::to_string(e + 1) + " (warp thread) never " +
                        "interlaces: it stays " + (up == 0 ? "under" : "over") + " all " +
                        std::to_string(m.picks) + " picks of the repeat, so nothing holds it");
  }
  for (int p = 0; p < m.picks; ++p) {
    int up = 0;
    for (int e = 0; e < m.ends; ++e)
      up += m.warp_up(p, e) ? 1 : 0;
    if (up == 0 || up == m.ends)
      throw_input_error(where + ": pick " + std::to_string(p + 1) + " (weft thread) never " +
                        "interlaces: it stays " + (up == m.ends ? "under" : "over") + " all " +
                        std::to_string(m.ends) + " ends of the repeat, so nothing holds it");
  }
}

FloatLengths float_lengths(const WeaveMatrix& m) {
  FloatLengths out;
  // A run on a weavable matrix never covers the whole period, so start each scan just after a
  // change of face and walk one full period.
  for (int e = 0; e < m.ends; ++e) {
    int start = 0;
    while (start < m.picks && m.warp_up(start, e) == m.warp_up_wrapped(start - 1, e))
      ++start;
    int run = 0;
    for (int k = 0; k < m.picks; ++k) {
      const int p = (start + k) % m.picks;
      run = (k > 0 && m.warp_up(p, e) == m.warp_up_wrapped(p - 1, e)) ? run + 1 : 1;
      if (m.warp_up(p, e)) out.longest_warp_float = std::max(out.longest_warp_float, run);
    }
  }
  for (int p = 0; p < m.picks; ++p) {
    int start = 0;
    while (start < m.ends && m.warp_up(p, start) == m.warp_up_wrapped(p, start - 1))
      ++start;
    int run = 0;
    for (int k = 0; k < m.ends; ++k) {
      const int e = (start + k) % m.ends;
      run = (k > 0 && m.warp_up(p, e) == m.warp_up_wrapped(p, e - 1)) ? run + 1 : 1;
      if (!m.warp_up(p, e)) out.longest_weft_float = std::max(out.longest_weft_float, run);
    }
  }
  return out;
}

}  // namespace clothbake::weave

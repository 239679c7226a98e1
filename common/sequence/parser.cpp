#include "sequence/parser.hpp"

#include "config/file_read.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

namespace rover::sequence {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Token {
  std::string_view text;
  int col = 0;  // 1-based byte column
};

// One error on one line; thrown inside the line parser and caught per line, so a bad line
// never stops the check of the others.
struct LineError {
  int col;
  std::string message;
  std::string expected;
};

enum class Dimension { kLength, kAngle, kTime, kPercent };

const char* UnitsOf(Dimension d) {
  switch (d) {
    case Dimension::kLength: return "m or cm";
    case Dimension::kAngle: return "deg or rad";
    case Dimension::kTime: return "s";
    case Dimension::kPercent: return "%";
  }
  return "";
}

const char* ExampleOf(Dimension d) {
  switch (d) {
    case Dimension::kLength: return "e.g. 1.5 m";
    case Dimension::kAngle: return "e.g. 20 deg";
    case Dimension::kTime: return "e.g. 600 s";
    case Dimension::kPercent: return "e.g. 40 %";
  }
  return "";
}

// Scale of a known unit in its dimension, or 0 when the unit is unknown / of another kind.
double UnitScale(std::string_view unit, Dimension d, bool& known_elsewhere) {
  known_elsewhere = false;
  struct U { const char* name; Dimension dim; double scale; };
  static const U kUnits[] = {{"m", Dimension::kLength, 1.0},   {"cm", Dimension::kLength, 0.01},
                             {"deg", Dimension::kAngle, kDeg}, {"rad", Dimension::kAngle, 1.0},
                             {"s", Dimension::kTime, 1.0},     {"%", Dimension::kPercent, 1.0}};
  for (const U& u : kUnits) {
    if (unit == u.name) {
      if (u.dim == d) return u.scale;
      known_elsewhere = true;
      return 0.0;
    }
  }
  return 0.0;
}

std::string Quoted(std::string_view s) {
  std::string shown(s.substr(0, 30));
  if (s.size() > 30) shown += "...";
  return "'" + shown + "'";
}

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool IsNonFiniteWord(std::string_view s) {
  std::string l = Lower(s);
  if (!l.empty() && (l[0] == '+' || l[0] == '-')) l.erase(0, 1);
  return l.rfind("nan", 0) == 0 || l.rfind("inf", 0) == 0;
}

// Length of the number at the start of s: [+-]? (d+ [. d*] | . d+) ([eE] [+-]? d+)?
std::size_t NumberLength(std::string_view s) {
  std::size_t i = 0;
  auto digits = [&] {
    std::size_t start = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    return i - start;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t int_digits = digits();
  std::size_t frac_digits = 0;
  if (i < s.size() && s[i] == '.') {
    ++i;
    frac_digits = digits();
  }
  if (int_digits + frac_digits == 0) return 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    std::size_t save = i;
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) i = save;
  }
  return i;
}

std::string Format(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

class LineParser {
 public:
  LineParser(std::vector<Token> tokens, int end_col, const LanguageLimits& limits)
      : tokens_(std::move(tokens)), end_col_(end_col), limits_(limits) {}

  bool AtEnd() const { return pos_ >= tokens_.size(); }
  const Token& Peek() const {
    static const Token kEnd{};
    return AtEnd() ? kEnd : tokens_[pos_];
  }
  int NextCol() const { return AtEnd() ? end_col_ : Peek().col; }
  bool PeekIs(std::string_view word) const { return !AtEnd() && Peek().text == word; }

  [[noreturn]] void Fail(int col, std::string message, std::string expected) const {
    throw LineError{col, std::move(message), std::move(expected)};
  }

  Token Next(const std::string& what, const std::string& expected) {
    if (AtEnd()) Fail(end_col_, "missing " + what, expected);
    return tokens_[pos_++];
  }

  void Expect(std::string_view word, const std::string& context) {
    if (AtEnd()) Fail(end_col_, "missing '" + std::string(word) + "' " + context, std::string(word));
    if (Peek().text != word) {
      Fail(Peek().col, "unexpected " + Quoted(Peek().text) + " " + context, std::string(word));
    }
    ++pos_;
  }

  // A word from a fixed set; returns its index.
  std::size_t Choice(const std::vector<std::string_view>& words, const std::string& what) {
    std::string list;
    for (std::size_t i = 0; i < words.size(); ++i) {
      list += (i == 0 ? "" : (i + 1 == words.size() ? " or " : ", ")) + std::string(words[i]);
    }
    if (AtEnd()) Fail(end_col_, "missing " + what, list);
    for (std::size_t i = 0; i < words.size(); ++i) {
      if (Peek().text == words[i]) {
        ++pos_;
        return i;
      }
    }
    Fail(Peek().col, "unknown " + what + " " + Quoted(Peek().text), list);
  }

  void ExpectEnd() {
    if (!AtEnd()) {
      Fail(Peek().col, "unexpected " + Quoted(Peek().text) + " after the command",
           "end of line or a # comment");
    }
  }

  // A number with its unit: "2.5 m", "2.5m", "40 %". Returns SI (percent stays percent).
  // `value_col` receives the column of the number, for range errors.
  double Quantity(Dimension d, const std::string& what, int* value_col = nullptr) {
    const std::string expected = std::string("a number with its unit, ") + UnitsOf(d) + ", " +
                                 ExampleOf(d);
    if (AtEnd()) Fail(end_col_, "missing " + what, expected);
    const Token tok = tokens_[pos_++];
    if (value_col) *value_col = tok.col;
    if (IsNonFiniteWord(tok.text)) {
      Fail(tok.col, what + " is not a finite number: " + Quoted(tok.text), "a finite number");
    }
    const std::size_t n = NumberLength(tok.text);
    if (n == 0) Fail(tok.col, "expected a number for " + what + ", got " + Quoted(tok.text), expected);
    double value = 0.0;
    const auto res = std::from_chars(tok.text.data() + (tok.text[0] == '+' ? 1 : 0),
                                     tok.text.data() + n, value);
    if (res.ec == std::errc::result_out_of_range || !std::isfinite(value)) {
      Fail(tok.col, what + " is not a finite number: " + Quoted(tok.text.substr(0, n)),
           "a finite number");
    }
    if (res.ec != std::errc()) {
      Fail(tok.col, "expected a number for " + what + ", got " + Quoted(tok.text), expected);
    }
    // The unit: attached ("60cm") or the next token ("60 cm").
    std::string_view unit;
    int unit_col = 0;
    if (n < tok.text.size()) {
      unit = tok.text.substr(n);
      unit_col = tok.col + static_cast<int>(n);
    } else {
      if (AtEnd()) {
        Fail(tok.col, "missing unit after " + std::string(tok.text) + " for " + what,
             UnitsOf(d));
      }
      FailOnDecimalComma(tok, what);
      const std::size_t next_number = NumberLength(Peek().text);
      const bool looks_numeric = next_number > 0 || IsNonFiniteWord(Peek().text) ||
                                 Peek().text == ",";
      bool elsewhere = false;
      const double s = UnitScale(Peek().text, d, elsewhere);
      if (looks_numeric || (s == 0.0 && !elsewhere && Peek().text != "%" &&
                            !LooksLikeUnit(Peek().text))) {
        Fail(tok.col, "missing unit after " + std::string(tok.text) + " for " + what,
             UnitsOf(d));
      }
      unit = Peek().text;
      unit_col = Peek().col;
      ++pos_;
    }
    bool elsewhere = false;
    const double scale = UnitScale(unit, d, elsewhere);
    if (scale == 0.0) {
      if (elsewhere) {
        Fail(unit_col, "wrong unit " + Quoted(unit) + " for " + what, UnitsOf(d));
      }
      Fail(unit_col, "unknown unit " + Quoted(unit) + " for " + what, UnitsOf(d));
    }
    const double si = value * scale;
    if (!std::isfinite(si)) Fail(tok.col, what + " is not a finite number", "a finite number");
    return si;
  }

  int Integer(const std::string& what, int lo, int hi) {
    const std::string expected = "a whole number in [" + std::to_string(lo) + ", " +
                                 std::to_string(hi) + "]";
    if (AtEnd()) Fail(end_col_, "missing " + what, expected);
    const Token tok = tokens_[pos_++];
    if (IsNonFiniteWord(tok.text)) {
      Fail(tok.col, what + " is not a finite number: " + Quoted(tok.text), expected);
    }
    long long value = 0;
    const auto res = std::from_chars(tok.text.data(), tok.text.data() + tok.text.size(), value);
    if (res.ec != std::errc() || res.ptr != tok.text.data() + tok.text.size()) {
      Fail(tok.col, "expected a whole number for " + what + ", got " + Quoted(tok.text), expected);
    }
    if (value < lo || value > hi) {
      Fail(tok.col, what + " " + std::string(tok.text) + " is out of range", expected);
    }
    return static_cast<int>(value);
  }

  std::string Name(const std::string& what) {
    const std::string expected = "a name of letters, digits, '_' or '-', starting with a letter";
    if (AtEnd()) Fail(end_col_, "missing " + what, expected);
    const Token tok = tokens_[pos_++];
    bool ok = std::isalpha(static_cast<unsigned char>(tok.text[0])) && tok.text.size() <= 64;
    for (char c : tok.text) {
      ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-');
    }
    if (!ok) Fail(tok.col, "bad " + what + " " + Quoted(tok.text), expected);
    return std::string(tok.text);
  }

  // lo < v <= hi (open_lo) or lo <= v <= hi; `shown_scale` converts SI back for messages.
  void Range(double v, int col, const std::string& what, double lo, double hi, bool open_lo,
             double shown_scale, const std::string& unit) const {
    const bool bad = open_lo ? !(v > lo) : !(v >= lo);
    if (bad || v > hi) {
      Fail(col, what + " " + Format(v / shown_scale) + " " + unit + " is out of range",
           std::string(open_lo ? "> " : ">= ") + Format(lo / shown_scale) + " " + unit +
               " and <= " + Format(hi / shown_scale) + " " + unit);
    }
  }

  const LanguageLimits& limits() const { return limits_; }

 private:
  // "1,5 m" (a decimal comma, as many locales write it) reads as the number 1 followed by a
  // ',' and would be reported as a missing unit: say what is wrong instead. Only a comma
  // touching digits on both sides counts; "1 m 2 m, 3 m 2 m" (polygon vertices) is spaced.
  void FailOnDecimalComma(const Token& number, const std::string& what) const {
    if (pos_ + 1 >= tokens_.size() || tokens_[pos_].text != ",") return;
    const Token& comma = tokens_[pos_];
    const Token& after = tokens_[pos_ + 1];
    const bool touching = comma.col == number.col + static_cast<int>(number.text.size()) &&
                          after.col == comma.col + 1;
    if (!touching || after.text.empty() || !std::isdigit(static_cast<unsigned char>(after.text[0]))) return;
    const std::size_t digits = NumberLength(after.text);
    const std::string fraction(after.text.substr(0, digits));
    Fail(comma.col, "decimal comma in " + Quoted(std::string(number.text) + "," + fraction) + " for " + what,
         "a decimal point: " + std::string(number.text) + "." + fraction);
  }

  static bool LooksLikeUnit(std::string_view t) {
    // Any token right after a number is taken as its (possibly unknown) unit, so that
    // "3 ft" says "unknown unit"; keywords of the language are not units.
    static const char* kKeywords[] = {"radius", "distance", "within", "time", "step", "maxturn",
                                      "failures", "wait", "noprogress", "over", "roll", "pitch",
                                      "then", "polygon", "circle", "slope", "slip"};
    for (const char* k : kKeywords) {
      if (t == k) return false;
    }
    return true;
  }

  std::vector<Token> tokens_;
  std::size_t pos_ = 0;
  int end_col_;
  const LanguageLimits& limits_;
};

// ---- UTF-8 and control characters ----
// Returns the 0-based offset of the first bad byte in [begin, end), or npos.
std::size_t FirstBadByte(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size()) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      if ((c < 0x20 && c != '\t') || c == 0x7f) return i;
      ++i;
      continue;
    }
    std::size_t len = 0;
    unsigned int cp = 0;
    if ((c & 0xE0) == 0xC0) { len = 2; cp = c & 0x1F; }
    else if ((c & 0xF0) == 0xE0) { len = 3; cp = c & 0x0F; }
    else if ((c & 0xF8) == 0xF0) { len = 4; cp = c & 0x07; }
    else return i;
    if (i + len > s.size()) return i;
    for (std::size_t k = 1; k < len; ++k) {
      const unsigned char cc = static_cast<unsigned char>(s[i + k]);
      if ((cc & 0xC0) != 0x80) return i;
      cp = (cp << 6) | (cc & 0x3F);
    }
    // Overlong forms, surrogates and values past U+10FFFF are not valid UTF-8.
    if ((len == 2 && cp < 0x80) || (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) ||
        (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) {
      return i;
    }
    i += len;
  }
  return std::string_view::npos;
}

// ---- polygons ----
double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

bool SegmentsIntersect(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2,
                       const Eigen::Vector2d& q1, const Eigen::Vector2d& q2) {
  const double d1 = Cross(p2 - p1, q1 - p1), d2 = Cross(p2 - p1, q2 - p1);
  const double d3 = Cross(q2 - q1, p1 - q1), d4 = Cross(q2 - q1, p2 - q1);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    return true;
  }
  auto on_segment = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p,
                       double cross) {
    return std::abs(cross) < 1e-12 && p.x() >= std::min(a.x(), b.x()) - 1e-12 &&
           p.x() <= std::max(a.x(), b.x()) + 1e-12 && p.y() >= std::min(a.y(), b.y()) - 1e-12 &&
           p.y() <= std::max(a.y(), b.y()) + 1e-12;
  };
  return on_segment(p1, p2, q1, d1) || on_segment(p1, p2, q2, d2) || on_segment(q1, q2, p1, d3) ||
         on_segment(q1, q2, p2, d4);
}

// ---- the commands ----
class SequenceParser {
 public:
  SequenceParser(const LanguageLimits& limits) : limits_(limits) {}

  Action Parse(LineParser& p) {
    const std::vector<std::string_view> kCommands = {
        "drive", "arc", "turn", "turnto", "goto", "vo", "slip", "tilt", "limit", "keepout",
        "site", "images"};
    const Token first = p.Peek();
    std::size_t which = kCommands.size();
    for (std::size_t i = 0; i < kCommands.size(); ++i) {
      if (first.text == kCommands[i]) which = i;
    }
    if (which == kCommands.size()) {
      p.Fail(first.col, "unknown command " + Quoted(first.text),
             "drive, arc, turn, turnto, goto, vo, slip, tilt, limit, keepout, site or images");
    }
    p.Next("command", "");
    Action action;
    switch (which) {
      case 0: action = ParseDrive(p); break;
      case 1: action = ParseArc(p); break;
      case 2: action = ParseTurn(p); break;
      case 3: action = ParseTurnTo(p); break;
      case 4: action = ParseGoto(p); break;
      case 5: action = ParseVo(p); break;
      case 6: action = ParseSlip(p); break;
      case 7: action = ParseTilt(p); break;
      case 8: action = ParseLimit(p); break;
      case 9: action = ParseKeepOut(p); break;
      case 10:
        zones_.clear();  // zones are in the old site frame; the executor clears them too
        action = NewSite{};
        break;
      default: action = ParseImages(p); break;
    }
    p.ExpectEnd();
    return action;
  }

  // Zones in force, by name, with the line that declared them (duplicate-name check).
  void CommitZones() { committed_zones_ = zones_; }
  void RollbackZones() { zones_ = committed_zones_; }

 private:
  Drive ParseDrive(LineParser& p) {
    int col = 0;
    Drive d;
    d.distance_m = p.Quantity(Dimension::kLength, "drive distance", &col);
    NonZeroAbs(p, d.distance_m, col, "drive distance", limits_.max_drive_m, 1.0, "m");
    return d;
  }

  Arc ParseArc(LineParser& p) {
    Arc a;
    int col = 0;
    p.Expect("radius", "after 'arc'");
    a.radius_m = p.Quantity(Dimension::kLength, "arc radius", &col);
    if (!(std::abs(a.radius_m) >= limits_.min_arc_radius_m) ||
        std::abs(a.radius_m) > limits_.max_arc_radius_m) {
      p.Fail(col, "arc radius " + Format(a.radius_m) + " m is out of range",
             "|radius| >= " + Format(limits_.min_arc_radius_m) + " m and <= " +
                 Format(limits_.max_arc_radius_m) + " m; + curves right, - curves left");
    }
    p.Expect("distance", "after the arc radius");
    a.distance_m = p.Quantity(Dimension::kLength, "arc distance", &col);
    NonZeroAbs(p, a.distance_m, col, "arc distance", limits_.max_drive_m, 1.0, "m");
    return a;
  }

  Turn ParseTurn(LineParser& p) {
    Turn t;
    int col = 0;
    if (p.PeekIs("to")) {  // "turn to -10 deg": the operator wants an absolute heading
      p.Fail(p.NextCol(), "unexpected 'to' after 'turn' (turn takes a relative angle)",
             "a relative angle, e.g. turn 20 deg; for an absolute heading: turnto -10 deg");
    }
    t.angle_rad = p.Quantity(Dimension::kAngle, "turn angle", &col);
    NonZeroAbs(p, t.angle_rad, col, "turn angle", limits_.max_turn_deg * kDeg, kDeg, "deg");
    return t;
  }

  TurnTo ParseTurnTo(LineParser& p) {
    TurnTo t;
    int col = 0;
    t.heading_rad = p.Quantity(Dimension::kAngle, "heading", &col);
    p.Range(t.heading_rad, col, "heading", -360.0 * kDeg, 360.0 * kDeg, false, kDeg, "deg");
    return t;
  }

  Goto ParseGoto(LineParser& p) {
    Goto g;
    int col = 0;
    g.target.x() = p.Quantity(Dimension::kLength, "goto x (north)", &col);
    Coordinate(p, g.target.x(), col, "goto x");
    g.target.y() = p.Quantity(Dimension::kLength, "goto y (east)", &col);
    Coordinate(p, g.target.y(), col, "goto y");
    p.Expect("within", "after the goto target");
    g.tolerance_m = p.Quantity(Dimension::kLength, "goto tolerance", &col);
    p.Range(g.tolerance_m, col, "goto tolerance", 0.0, limits_.max_goto_tolerance_m, true, 1.0, "m");
    bool seen_time = false, seen_distance = false, seen_avoid = false;
    while (!p.AtEnd()) {
      const int opt_col = p.Peek().col;
      const std::size_t which = p.Choice({"time", "distance", "avoid"}, "goto option");
      if (which == 2) {
        if (seen_avoid) p.Fail(opt_col, "'avoid' given twice", "each goto option at most once");
        seen_avoid = true;
        g.avoid = p.Choice({"on", "off"}, "goto avoid mode") == 0;
      } else if (which == 0) {
        if (seen_time) p.Fail(opt_col, "'time' given twice", "each goto option at most once");
        seen_time = true;
        g.time_limit_s = p.Quantity(Dimension::kTime, "goto time limit", &col);
        p.Range(*g.time_limit_s, col, "goto time limit", 0.0, limits_.max_time_s, true, 1.0, "s");
      } else {
        if (seen_distance) p.Fail(opt_col, "'distance' given twice", "each goto option at most once");
        seen_distance = true;
        g.distance_limit_m = p.Quantity(Dimension::kLength, "goto distance limit", &col);
        p.Range(*g.distance_limit_m, col, "goto distance limit", 0.0, limits_.max_distance_limit_m,
                true, 1.0, "m");
      }
    }
    return g;
  }

  Action ParseVo(LineParser& p) {
    const std::size_t mode = p.Choice({"on", "off", "lost"}, "VO mode");
    if (mode == 2) return ParseVoLost(p);
    VoSetting v;
    v.enabled = mode == 0;
    std::vector<bool> seen(4, false);
    while (!p.AtEnd()) {
      const int opt_col = p.Peek().col;
      const std::size_t which = v.enabled ? p.Choice({"step", "maxturn", "failures", "wait"}, "vo option")
                                          : p.Choice({"step", "maxturn"}, "vo off option");
      if (seen[which]) p.Fail(opt_col, "option given twice", "each vo option at most once");
      seen[which] = true;
      int col = 0;
      if (which == 0) {
        v.step_m = p.Quantity(Dimension::kLength, "step length", &col);
        p.Range(*v.step_m, col, "step length", 0.0, limits_.max_step_m, true, 1.0, "m");
      } else if (which == 1) {
        v.max_turn_rad = p.Quantity(Dimension::kAngle, "max turn per step", &col);
        p.Range(*v.max_turn_rad, col, "max turn per step", 0.0,
                limits_.max_turn_per_step_deg * kDeg, true, kDeg, "deg");
      } else if (which == 2) {
        v.max_failures = p.Integer("acceptable VO failures", 0, limits_.max_vo_failures);
        p.Expect("then", "after the failure count");
        v.past_max = p.Choice({"abort", "continue"}, "VO failure action") == 0
                         ? VoFailureAction::kAbort
                         : VoFailureAction::kContinue;
      } else {
        v.wait_s = p.Quantity(Dimension::kTime, "VO wait", &col);
        p.Range(*v.wait_s, col, "VO wait", 0.0, limits_.max_time_s, true, 1.0, "s");
      }
    }
    return v;
  }

  // vo lost abort|shorten|retry N [slope A] [slip P]
  VoLostSetting ParseVoLost(LineParser& p) {
    VoLostSetting l;
    const std::size_t action = p.Choice({"abort", "shorten", "retry"}, "VO lost action");
    l.action = action == 0 ? VoLostAction::kAbort : action == 1 ? VoLostAction::kShorten
                                                                 : VoLostAction::kRetry;
    if (l.action == VoLostAction::kRetry) {
      l.retries = p.Integer("number of retries", 1, limits_.max_vo_retries);
    }
    while (!p.AtEnd()) {
      const int opt_col = p.Peek().col;
      int col = 0;
      if (p.Choice({"slope", "slip"}, "vo lost option") == 0) {
        if (l.slope_rad) p.Fail(opt_col, "'slope' given twice", "each vo lost option at most once");
        l.slope_rad = p.Quantity(Dimension::kAngle, "slip-prone slope", &col);
        p.Range(*l.slope_rad, col, "slip-prone slope", 0.0, limits_.max_tilt_deg * kDeg, true, kDeg,
                "deg");
      } else {
        if (l.slip_pct) p.Fail(opt_col, "'slip' given twice", "each vo lost option at most once");
        l.slip_pct = p.Quantity(Dimension::kPercent, "slip-prone slip", &col);
        p.Range(*l.slip_pct, col, "slip-prone slip", 0.0, 100.0, true, 1.0, "%");
      }
    }
    return l;
  }

  SlipSetting ParseSlip(LineParser& p) {
    SlipSetting s;
    if (p.Choice({"limit", "off"}, "slip mode") == 1) return s;
    s.enabled = true;
    int col = 0;
    s.limit_pct = p.Quantity(Dimension::kPercent, "slip limit", &col);
    p.Range(s.limit_pct, col, "slip limit", 0.0, 100.0, true, 1.0, "%");
    if (!p.AtEnd()) {
      p.Expect("noprogress", "after the slip limit");
      const double pct = p.Quantity(Dimension::kPercent, "no-progress fraction", &col);
      if (!(pct >= 0.0) || !(pct < 100.0)) {
        p.Fail(col, "no-progress fraction " + Format(pct) + " % is out of range", ">= 0 % and < 100 %");
      }
      s.no_progress_fraction = pct / 100.0;
      p.Expect("over", "after the no-progress fraction");
      s.over_steps = p.Integer("number of steps", 1, limits_.max_over_steps);
      p.Choice({"steps", "step"}, "word");
    }
    return s;
  }

  TiltSetting ParseTilt(LineParser& p) {
    TiltSetting t;
    if (p.PeekIs("off")) {
      p.Next("", "");
      return t;
    }
    t.enabled = true;
    std::size_t which = p.Choice({"roll", "pitch"}, "tilt axis");
    while (true) {
      int col = 0;
      std::optional<double>& slot = which == 0 ? t.roll_rad : t.pitch_rad;
      const char* what = which == 0 ? "roll limit" : "pitch limit";
      slot = p.Quantity(Dimension::kAngle, what, &col);
      p.Range(*slot, col, what, 0.0, limits_.max_tilt_deg * kDeg, true, kDeg, "deg");
      if (p.AtEnd()) break;
      const int opt_col = p.Peek().col;
      which = p.Choice({"roll", "pitch"}, "tilt axis");
      if ((which == 0 && t.roll_rad) || (which == 1 && t.pitch_rad)) {
        p.Fail(opt_col, "axis given twice", "roll and pitch at most once each");
      }
    }
    return t;
  }

  LimitSetting ParseLimit(LineParser& p) {
    LimitSetting l;
    do {
      const int opt_col = p.NextCol();
      int col = 0;
      if (p.Choice({"time", "distance"}, "limit") == 0) {
        if (l.time_s) p.Fail(opt_col, "'time' given twice", "time and distance at most once each");
        l.time_s = p.Quantity(Dimension::kTime, "time limit", &col);
        p.Range(*l.time_s, col, "time limit", 0.0, limits_.max_time_s, true, 1.0, "s");
      } else {
        if (l.distance_m) p.Fail(opt_col, "'distance' given twice", "time and distance at most once each");
        l.distance_m = p.Quantity(Dimension::kLength, "distance limit", &col);
        p.Range(*l.distance_m, col, "distance limit", 0.0, limits_.max_distance_limit_m, true, 1.0, "m");
      }
    } while (!p.AtEnd());
    return l;
  }

  Action ParseKeepOut(LineParser& p) {
    if (p.AtEnd()) p.Fail(p.NextCol(), "missing zone name", "a zone name, 'remove NAME' or 'clear'");
    if (p.PeekIs("clear")) {
      p.Next("", "");
      zones_.clear();
      return KeepOutClear{};
    }
    if (p.PeekIs("remove")) {
      p.Next("", "");
      const int col = p.NextCol();
      KeepOutRemove r{p.Name("zone name")};
      if (zones_.erase(r.name) == 0) {
        if (const auto other = ZoneDifferingInCase(r.name)) {
          p.Fail(col, "no zone named " + Quoted(r.name) + " is in force (names are case-sensitive)",
                 "'keepout remove " + other->first + "' (declared at line " + std::to_string(other->second) + ")");
        }
        // Zones live as long as the sequence that declared them: the executor clears them,
        // for itself and the hazard monitor, when a sequence starts.
        p.Fail(col, "no zone named " + Quoted(r.name) + " is in force in this sequence",
               "the name of a zone declared earlier in this file (zones of an earlier sequence are "
               "cleared when this one starts)");
      }
      return r;
    }
    const int name_col = p.NextCol();
    KeepOutZone z;
    z.name = p.Name("zone name");
    if (auto it = zones_.find(z.name); it != zones_.end()) {
      p.Fail(name_col, "duplicate zone name " + Quoted(z.name) + " (first declared at line " +
                           std::to_string(it->second) + ")",
             "a new name, or 'keepout remove " + z.name + "' first");
    }
    // Names are case-sensitive (the executor and hazard monitor match them exactly), so
    // 'Mazatzal' and 'mazatzal' would be two zones that an operator reads as one: refused.
    if (const auto other = ZoneDifferingInCase(z.name)) {
      p.Fail(name_col, "zone name " + Quoted(z.name) + " differs only in case from zone " + Quoted(other->first) +
                           " (declared at line " + std::to_string(other->second) + ")",
             "a name that differs in more than case (names are case-sensitive), or 'keepout remove " +
                 other->first + "' first");
    }
    const int shape_col = p.NextCol();
    int col = 0;
    if (p.Choice({"circle", "polygon"}, "zone shape") == 0) {
      z.shape = KeepOutZone::Shape::kCircle;
      z.center.x() = p.Quantity(Dimension::kLength, "circle centre x (north)", &col);
      Coordinate(p, z.center.x(), col, "circle centre x");
      z.center.y() = p.Quantity(Dimension::kLength, "circle centre y (east)", &col);
      Coordinate(p, z.center.y(), col, "circle centre y");
      p.Expect("radius", "after the circle centre");
      z.radius_m = p.Quantity(Dimension::kLength, "circle radius", &col);
      p.Range(z.radius_m, col, "circle radius", 0.0, 1000.0, true, 1.0, "m");
    } else {
      z.shape = KeepOutZone::Shape::kPolygon;
      std::vector<int> cols;
      while (true) {
        Eigen::Vector2d v;
        int vcol = p.NextCol();
        v.x() = p.Quantity(Dimension::kLength, "polygon vertex x (north)", &col);
        Coordinate(p, v.x(), col, "polygon vertex x");
        v.y() = p.Quantity(Dimension::kLength, "polygon vertex y (east)", &col);
        Coordinate(p, v.y(), col, "polygon vertex y");
        if (static_cast<int>(z.vertices.size()) >= limits_.max_polygon_vertices) {
          p.Fail(vcol, "too many polygon vertices",
                 "at most " + std::to_string(limits_.max_polygon_vertices));
        }
        z.vertices.push_back(v);
        cols.push_back(vcol);
        if (p.AtEnd()) break;
        if (!p.PeekIs(",")) {
          p.Fail(p.Peek().col, "unexpected " + Quoted(p.Peek().text) + " in polygon",
                 "',' between vertices, e.g. 1 m 2 m, 3 m 2 m, 3 m 5 m");
        }
        p.Next("", "");
      }
      CheckPolygon(p, z.vertices, cols, shape_col);
    }
    zones_[z.name] = current_line_;
    return KeepOutAdd{z};
  }

  Images ParseImages(LineParser& p) {
    Images im;
    if (!p.AtEnd()) {
      im.purpose = p.Choice({"science", "baseline"}, "image purpose") == 0
                       ? ImagePurpose::kScience
                       : ImagePurpose::kVoBaseline;
    }
    return im;
  }

  // A zone in force whose name equals `name` but for case.
  std::optional<std::pair<std::string, int>> ZoneDifferingInCase(const std::string& name) const {
    for (const auto& [other, line] : zones_) {
      if (other != name && Lower(other) == Lower(name)) return std::make_pair(other, line);
    }
    return std::nullopt;
  }

  void CheckPolygon(LineParser& p, const std::vector<Eigen::Vector2d>& v, const std::vector<int>& cols,
                    int shape_col) const {
    const std::string expected = "at least 3 distinct vertices 'x y, x y, x y' forming a simple polygon";
    if (v.size() < 3) p.Fail(shape_col, "polygon has " + std::to_string(v.size()) + " vertices", expected);
    const std::size_t n = v.size();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        if ((v[i] - v[j]).norm() < 1e-6) {
          p.Fail(cols[i], "polygon vertex " + std::to_string(i + 1) + " repeats vertex " +
                              std::to_string(j + 1), expected);
        }
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
        if (adjacent) continue;
        if (SegmentsIntersect(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n])) {
          p.Fail(cols[j], "polygon edges " + std::to_string(i + 1) + " and " + std::to_string(j + 1) +
                              " cross", expected);
        }
      }
    }
    double area2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) area2 += Cross(v[i], v[(i + 1) % n]);
    if (std::abs(area2) < 1e-6) p.Fail(shape_col, "polygon has no area (collinear vertices)", expected);
  }

  void NonZeroAbs(LineParser& p, double v, int col, const std::string& what, double max_abs,
                  double shown_scale, const std::string& unit) const {
    if (v == 0.0 || std::abs(v) > max_abs) {
      p.Fail(col, what + " " + Format(v / shown_scale) + " " + unit + " is out of range",
             "non-zero, |value| <= " + Format(max_abs / shown_scale) + " " + unit);
    }
  }

  void Coordinate(LineParser& p, double v, int col, const std::string& what) const {
    p.Range(v, col, what, -limits_.max_coordinate_m, limits_.max_coordinate_m, false, 1.0, "m");
  }

 public:
  int current_line_ = 0;

 private:
  const LanguageLimits& limits_;
  std::map<std::string, int> zones_, committed_zones_;
};

}  // namespace

bool IsMotion(const Command& command) {
  return std::holds_alternative<Drive>(command.action) || std::holds_alternative<Arc>(command.action) ||
         std::holds_alternative<Turn>(command.action) || std::holds_alternative<TurnTo>(command.action) ||
         std::holds_alternative<Goto>(command.action);
}

std::string SequenceError::ToString() const {
  std::string s = source + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + message;
  if (!expected.empty()) s += " (expected " + expected + ")";
  return s;
}

ParseResult ParseSequence(std::string_view text, const std::string& source_name,
                          const LanguageLimits& limits) {
  ParseResult result;
  result.sequence.name = source_name;
  SequenceParser parser(limits);
  auto add_error = [&](int line, int col, std::string message, std::string expected) {
    if (static_cast<int>(result.errors.size()) < limits.max_errors) {
      result.errors.push_back({source_name, line, col, std::move(message), std::move(expected)});
    }
  };

  int line_no = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    if (start == text.size() && (text.empty() || text.back() == '\n')) break;
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);  // CRLF files

    if (const std::size_t bad = FirstBadByte(line); bad != std::string_view::npos) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned char>(line[bad]));
      add_error(line_no, static_cast<int>(bad) + 1,
                std::string("invalid byte ") + hex + " (binary data or not UTF-8)",
                "UTF-8 text without control characters");
      continue;
    }
    if (static_cast<int>(line.size()) > limits.max_line_bytes) {
      add_error(line_no, limits.max_line_bytes + 1, "line is too long",
                "at most " + std::to_string(limits.max_line_bytes) + " bytes per line");
      continue;
    }
    const std::size_t hash = line.find('#');
    std::string_view code = line.substr(0, hash);

    std::vector<Token> tokens;
    std::size_t i = 0;
    while (i < code.size()) {
      const char c = code[i];
      if (c == ' ' || c == '\t') {
        ++i;
      } else if (c == ',') {
        tokens.push_back({code.substr(i, 1), static_cast<int>(i) + 1});
        ++i;
      } else {
        std::size_t j = i;
        while (j < code.size() && code[j] != ' ' && code[j] != '\t' && code[j] != ',') ++j;
        tokens.push_back({code.substr(i, j - i), static_cast<int>(i) + 1});
        i = j;
      }
    }
    if (tokens.empty()) continue;
    std::size_t text_end = code.size();
    while (text_end > 0 && (code[text_end - 1] == ' ' || code[text_end - 1] == '\t')) --text_end;
    const int end_col = static_cast<int>(text_end) + 2;  // one past the last character, +1 space

    LineParser p(tokens, end_col, limits);
    parser.current_line_ = line_no;
    try {
      Command command;
      command.line = line_no;
      command.text = std::string(code.substr(tokens.front().col - 1, text_end - (tokens.front().col - 1)));
      command.action = parser.Parse(p);
      parser.CommitZones();
      result.sequence.commands.push_back(std::move(command));
    } catch (const LineError& e) {
      parser.RollbackZones();
      add_error(line_no, e.col, e.message, e.expected);
    }
  }

  if (result.errors.empty() && result.sequence.commands.empty()) {
    add_error(1, 1,
              text.empty() ? "empty sequence file" : "the sequence has no commands, only comments or blank lines",
              "at least one command, e.g. drive 1 m");
  }
  return result;
}

namespace {
std::string FirstErrorText(const std::vector<SequenceError>& errors) {
  return errors.empty() ? std::string("sequence check failed") : errors.front().ToString();
}
}  // namespace

SequenceCheckError::SequenceCheckError(std::vector<SequenceError> errors)
    : std::runtime_error(FirstErrorText(errors)), errors_(std::move(errors)) {}

Sequence ParseSequenceOrThrow(std::string_view text, const std::string& source_name,
                              const LanguageLimits& limits) {
  ParseResult r = ParseSequence(text, source_name, limits);
  if (!r.ok()) throw SequenceCheckError(std::move(r.errors));
  return std::move(r.sequence);
}

ParseResult ParseSequenceFile(const std::string& path, const LanguageLimits& limits) {
  std::string text;
  try {  // a regular file of at most 1 MiB: a FIFO or /dev/zero is refused, not read
    text = config::ReadBoundedRegularFile(path, config::kMaxSequenceFileBytes, "sequence file");
  } catch (const config::FileReadError& e) {
    ParseResult r;
    r.sequence.name = path;
    r.errors.push_back({path, 1, 1, e.problem(), e.expected()});
    return r;
  }
  return ParseSequence(text, path, limits);
}

}  // namespace rover::sequence

#include "sdk/command.hpp"

#include <cassert>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace shelfcross::sdk {
namespace {

struct VerbSpec {
  Verb verb;
  std::string_view text;
};

constexpr VerbSpec kVerbs[] = {
    {Verb::command, "command"},     {Verb::takeoff, "takeoff"},     {Verb::land, "land"},
    {Verb::emergency, "emergency"}, {Verb::stop, "stop"},           {Verb::streamon, "streamon"},
    {Verb::streamoff, "streamoff"}, {Verb::up, "up"},               {Verb::down, "down"},
    {Verb::left, "left"},           {Verb::right, "right"},         {Verb::forward, "forward"},
    {Verb::back, "back"},           {Verb::cw, "cw"},               {Verb::ccw, "ccw"},
    {Verb::flip, "flip"},           {Verb::go, "go"},               {Verb::curve, "curve"},
    {Verb::speed, "speed"},         {Verb::rc, "rc"},               {Verb::speed_q, "speed?"},
    {Verb::battery_q, "battery?"},  {Verb::time_q, "time?"},        {Verb::height_q, "height?"},
    {Verb::temp_q, "temp?"},        {Verb::attitude_q, "attitude?"}, {Verb::baro_q, "baro?"},
    {Verb::tof_q, "tof?"},          {Verb::wifi_q, "wifi?"},        {Verb::sdk_q, "sdk?"},
    {Verb::sn_q, "sn?"},            {Verb::acceleration_q, "acceleration?"},
};

ParseError unknown(std::string_view text) {
  return {ParseError::Kind::unknown_command, "unknown command: " + std::string(text),
          "unknown command '" + std::string(text) + "'"};
}
ParseError malformed(std::string reason) { return {ParseError::Kind::malformed, "error", std::move(reason)}; }
ParseError out_of_range(std::string reason) { return {ParseError::Kind::out_of_range, "out of range", std::move(reason)}; }

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

std::optional<int> to_int(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  int v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

// Argument count and per-argument inclusive range of each verb with integer arguments.
struct Range {
  int lo, hi;
};

}  // namespace

std::string_view verb_text(Verb verb) {
  for (const auto& v : kVerbs)
    if (v.verb == verb) return v.text;
  return "?";
}

bool is_read(Verb verb) { return verb >= Verb::speed_q; }

bool is_manoeuvre(Verb verb) {
  switch (verb) {
    case Verb::takeoff: case Verb::land: case Verb::up: case Verb::down: case Verb::left: case Verb::right:
    case Verb::forward: case Verb::back: case Verb::cw: case Verb::ccw: case Verb::flip: case Verb::go:
    case Verb::curve:
      return true;
    default:
      return false;
  }
}

std::string to_text(const Command& c) {
  std::string s(verb_text(c.verb));
  if (c.verb == Verb::flip) {
    s += ' ';
    s += c.flip_direction;
    return s;
  }
  for (int i = 0; i < c.arg_count; ++i) {
    s += ' ';
    s += std::to_string(c.args[i]);
  }
  return s;
}

std::variant<Command, ParseError> parse(std::string_view text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ' || text.back() == '\t'))
    text.remove_suffix(1);
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  const std::vector<std::string_view> tok = split(text);
  if (tok.empty()) return malformed("empty command");

  Command c;
  bool found = false;
  for (const auto& v : kVerbs)
    if (v.text == tok[0]) {
      c.verb = v.verb;
      found = true;
    }
  if (!found) return unknown(text);
  const std::string verb(tok[0]);
  const int nargs = static_cast<int>(tok.size()) - 1;

  if (c.verb == Verb::flip) {
    if (nargs != 1) return malformed("flip takes one of l r f b");
    if (tok[1] != "l" && tok[1] != "r" && tok[1] != "f" && tok[1] != "b")
      return out_of_range("flip direction must be l, r, f or b");
    c.flip_direction = tok[1][0];
    return c;
  }

  std::vector<Range> ranges;
  switch (c.verb) {
    case Verb::up: case Verb::down: case Verb::left: case Verb::right: case Verb::forward: case Verb::back:
      ranges = {{20, 500}};
      break;
    case Verb::cw: case Verb::ccw:
      ranges = {{1, 360}};
      break;
    case Verb::speed:
      ranges = {{10, 100}};
      break;
    case Verb::rc:
      ranges = {{-100, 100}, {-100, 100}, {-100, 100}, {-100, 100}};
      break;
    case Verb::go:
      ranges = {{-500, 500}, {-500, 500}, {-500, 500}, {10, 100}};
      break;
    case Verb::curve:
      ranges = {{-500, 500}, {-500, 500}, {-500, 500}, {-500, 500}, {-500, 500}, {-500, 500}, {10, 60}};
      break;
    default:
      break;
  }
  if (nargs != static_cast<int>(ranges.size()))
    return malformed(verb + " takes " + std::to_string(ranges.size()) + " argument(s), got " + std::to_string(nargs));
  for (int i = 0; i < nargs; ++i) {
    const auto v = to_int(tok[i + 1]);
    if (!v) return malformed(verb + ": argument " + std::to_string(i + 1) + " '" + std::string(tok[i + 1]) + "' is not an integer");
    if (*v < ranges[i].lo || *v > ranges[i].hi)
      return out_of_range(verb + ": argument " + std::to_string(i + 1) + " = " + std::to_string(*v) + " is outside " +
                          std::to_string(ranges[i].lo) + ".." + std::to_string(ranges[i].hi));
    c.args[i] = *v;
  }
  c.arg_count = nargs;

  if (c.verb == Verb::go && std::abs(c.args[0]) <= 20 && std::abs(c.args[1]) <= 20 && std::abs(c.args[2]) <= 20)
    return out_of_range("go: x, y, z all within -20..20");
  if (c.verb == Verb::curve) {
    // The arc from the current point through (x1 y1 z1) to (x2 y2 z2): radius 0.5..10 m.
    const double a[3] = {double(c.args[0]), double(c.args[1]), double(c.args[2])};
    const double b[3] = {double(c.args[3]), double(c.args[4]), double(c.args[5])};
    const double cr[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const double na = std::hypot(a[0], a[1], a[2]), nb = std::hypot(b[0], b[1], b[2]);
    const double nab = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    const double ncr = std::hypot(cr[0], cr[1], cr[2]);
    if (ncr == 0.0) return out_of_range("curve: the three points are collinear");
    const double radius_cm = na * nb * nab / (2.0 * ncr);
    if (radius_cm < 50.0 || radius_cm > 1000.0) return out_of_range("curve: arc radius outside 0.5..10 m");
  }
  return c;
}

CommandKind kind_of(Verb verb) {
  switch (verb) {
    case Verb::command: case Verb::streamon: case Verb::streamoff:
      return CommandKind::Control;
    case Verb::rc:
      return CommandKind::Rc;
    default:
      return is_read(verb) ? CommandKind::Read : CommandKind::Motion;
  }
}

std::optional<CommandKind> classify_command(std::string_view text, std::string* why) {
  const auto fail = [why](std::string reason) -> std::optional<CommandKind> {
    if (why) *why = std::move(reason);
    return std::nullopt;
  };
  if (text.empty()) return fail("empty command");
  for (const char ch : text)
    if (ch < 0x20 || ch > 0x7e) return fail("non-printable character in command");
  const auto parsed = parse(text);
  if (const auto* err = std::get_if<ParseError>(&parsed)) return fail(err->reason);
  const Command& c = std::get<Command>(parsed);
  const std::string canonical = to_text(c);
  if (canonical != text)
    return fail("not in canonical form (one space between tokens, no leading or trailing space, integers "
                "without '+' or leading zeros): '" + std::string(text) + "' is '" + canonical + "'");
  return kind_of(c.verb);
}

std::string rc_text(int a, int b, int c, int d) {
  assert(std::abs(a) <= 100 && std::abs(b) <= 100 && std::abs(c) <= 100 && std::abs(d) <= 100);
  return "rc " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + " " + std::to_string(d);
}

bool is_rc_text(std::string_view text) { return text == "rc" || text.substr(0, 3) == "rc "; }

TimeNs ReplyTimeouts::timeout_for(std::string_view text) const {
  if (text == "takeoff") return seconds_to_ns(takeoff_s);
  if (text == "land") return seconds_to_ns(land_s);
  return seconds_to_ns(default_s);
}

}  // namespace shelfcross::sdk

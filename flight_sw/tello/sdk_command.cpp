#include "flight_sw/tello/sdk_command.hpp"

#include <array>
#include <cassert>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace shelfcross::tello {
namespace {

std::vector<std::string_view> split_spaces(std::string_view text) {
  std::vector<std::string_view> tokens;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t space = text.find(' ', start);
    const size_t end = space == std::string_view::npos ? text.size() : space;
    tokens.push_back(text.substr(start, end - start));
    if (space == std::string_view::npos) break;
    start = space + 1;
  }
  return tokens;
}

// A canonical decimal integer: optional '-', digits, no leading zero unless "0", no "-0".
std::optional<int> to_int(std::string_view s) {
  if (s.empty() || s.size() > 6) return std::nullopt;
  const std::string_view digits = s.front() == '-' ? s.substr(1) : s;
  if (digits.empty() || (digits.size() > 1 && digits.front() == '0')) return std::nullopt;
  if (s.front() == '-' && digits == "0") return std::nullopt;
  int v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

bool fail(std::string* why, std::string reason) {
  if (why) *why = std::move(reason);
  return false;
}

// Integer arguments args[first .. first+count) each in [lo, hi].
bool int_args(const std::vector<std::string_view>& t, size_t first, size_t count, int lo, int hi,
              std::vector<int>& out, std::string* why) {
  for (size_t i = first; i < first + count; ++i) {
    const auto v = to_int(t[i]);
    if (!v) return fail(why, "argument '" + std::string(t[i]) + "' is not an integer");
    if (*v < lo || *v > hi) {
      return fail(why, "argument " + std::to_string(*v) + " outside " + std::to_string(lo) +
                           ".." + std::to_string(hi));
    }
    out.push_back(*v);
  }
  return true;
}

bool within20(int v) { return v >= -20 && v <= 20; }

}  // namespace

std::optional<CommandKind> classify_command(std::string_view text, std::string* why) {
  if (text.empty()) return fail(why, "empty command"), std::nullopt;
  for (char c : text) {
    if (c < 0x20 || c > 0x7e) return fail(why, "non-printable character in command"), std::nullopt;
  }
  const auto t = split_spaces(text);
  for (auto tok : t) {
    if (tok.empty()) return fail(why, "empty token (double, leading or trailing space)"), std::nullopt;
  }
  const std::string_view verb = t[0];
  const size_t nargs = t.size() - 1;
  auto arity = [&](size_t n) {
    if (nargs == n) return true;
    std::string reason(verb);
    reason.append(" takes ").append(std::to_string(n)).append(" argument(s), got ");
    reason.append(std::to_string(nargs));
    return fail(why, reason);
  };
  std::vector<int> v;
  static constexpr std::array kControl{"command", "streamon", "streamoff"};
  static constexpr std::array kPlainMotion{"takeoff", "land", "emergency", "stop"};
  static constexpr std::array kReads{"speed?", "battery?", "time?", "height?", "temp?", "attitude?",
                                     "baro?", "tof?", "wifi?", "sdk?", "sn?"};
  static constexpr std::array kMoves{"up", "down", "left", "right", "forward", "back"};
  for (auto c : kControl) {
    if (verb == c) return arity(0) ? std::optional(CommandKind::Control) : std::nullopt;
  }
  for (auto c : kPlainMotion) {
    if (verb == c) return arity(0) ? std::optional(CommandKind::Motion) : std::nullopt;
  }
  for (auto c : kReads) {
    if (verb == c) return arity(0) ? std::optional(CommandKind::Read) : std::nullopt;
  }
  for (auto c : kMoves) {
    if (verb == c) {
      if (!arity(1) || !int_args(t, 1, 1, 20, 500, v, why)) return std::nullopt;
      return CommandKind::Motion;
    }
  }
  if (verb == "cw" || verb == "ccw") {
    if (!arity(1) || !int_args(t, 1, 1, 1, 360, v, why)) return std::nullopt;
    return CommandKind::Motion;
  }
  if (verb == "flip") {
    if (!arity(1)) return std::nullopt;
    if (t[1] != "l" && t[1] != "r" && t[1] != "f" && t[1] != "b") {
      return fail(why, "flip direction must be l, r, f or b"), std::nullopt;
    }
    return CommandKind::Motion;
  }
  if (verb == "speed") {
    if (!arity(1) || !int_args(t, 1, 1, 10, 100, v, why)) return std::nullopt;
    return CommandKind::Motion;
  }
  if (verb == "go") {
    if (!arity(4) || !int_args(t, 1, 3, -500, 500, v, why) || !int_args(t, 4, 1, 10, 100, v, why)) {
      return std::nullopt;
    }
    if (within20(v[0]) && within20(v[1]) && within20(v[2])) {
      return fail(why, "go: x, y and z all within -20..20"), std::nullopt;
    }
    return CommandKind::Motion;
  }
  if (verb == "curve") {
    if (!arity(7) || !int_args(t, 1, 6, -500, 500, v, why) || !int_args(t, 7, 1, 10, 60, v, why)) {
      return std::nullopt;
    }
    // Circumradius of the triangle (origin, p1, p2): R = |p1| |p2| |p2 - p1| / (2 |p1 x p2|).
    const double x1 = v[0], y1 = v[1], z1 = v[2], x2 = v[3], y2 = v[4], z2 = v[5];
    const double cx = y1 * z2 - z1 * y2, cy = z1 * x2 - x1 * z2, cz = x1 * y2 - y1 * x2;
    const double cross = std::sqrt(cx * cx + cy * cy + cz * cz);
    const double a = std::sqrt(x1 * x1 + y1 * y1 + z1 * z1);
    const double b = std::sqrt(x2 * x2 + y2 * y2 + z2 * z2);
    const double c = std::sqrt((x2 - x1) * (x2 - x1) + (y2 - y1) * (y2 - y1) + (z2 - z1) * (z2 - z1));
    if (cross < 1e-9) return fail(why, "curve: points collinear with the origin"), std::nullopt;
    const double radius_cm = a * b * c / (2.0 * cross);
    if (radius_cm < 50.0 || radius_cm > 1000.0) {
      return fail(why, "curve: arc radius outside 0.5..10 m"), std::nullopt;
    }
    return CommandKind::Motion;
  }
  if (verb == "rc") {
    if (!arity(4) || !int_args(t, 1, 4, -100, 100, v, why)) return std::nullopt;
    return CommandKind::Rc;
  }
  fail(why, "unknown command '" + std::string(verb) + "'");
  return std::nullopt;
}

std::string rc_text(int a, int b, int c, int d) {
  assert(std::abs(a) <= 100 && std::abs(b) <= 100 && std::abs(c) <= 100 && std::abs(d) <= 100);
  return "rc " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + " " +
         std::to_string(d);
}

TimeNs ReplyTimeouts::timeout_for(std::string_view text) const {
  if (text == "takeoff") return takeoff_ns;
  if (text == "land") return land_ns;
  return default_ns;
}

}  // namespace shelfcross::tello

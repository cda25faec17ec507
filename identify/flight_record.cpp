#include "identify/flight_record.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <variant>

#include <nlohmann/json.hpp>

#include "sdk/command.hpp"
#include "sdk/state_record.hpp"

namespace shelfcross::identify {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& name, int line, const std::string& why) {
  throw FlightLogFormatError(name + ":" + std::to_string(line) + ": " + why);
}

std::string seconds_text(TimeNs t_ns) {
  std::ostringstream s;
  s.precision(6);
  s << std::fixed << ns_to_seconds(t_ns) << " s";
  return s.str();
}

// "rc a b c d" with four integers in -100..100 (sdk::parse's), or nothing.
std::optional<std::array<int, 4>> parse_rc(const std::string& text) {
  const auto parsed = sdk::parse(text);
  const auto* c = std::get_if<sdk::Command>(&parsed);
  if (!c || c->verb != sdk::Verb::rc) return std::nullopt;
  return std::array<int, 4>{c->args[0], c->args[1], c->args[2], c->args[3]};
}

// Each stream the identification reads must be in time order: a log whose records go back in
// time was edited or concatenated, and a fit over it would be meaningless.
struct OrderCheck {
  const char* what;
  TimeNs last_ns = 0;
  int last_line = 0;
  void check(const std::string& name, int line, TimeNs t_ns) {
    if (last_line > 0 && t_ns < last_ns) {
      fail(name, line, std::string(what) + " at t = " + seconds_text(t_ns) + " is earlier than the one on line " +
                           std::to_string(last_line) + " (t = " + seconds_text(last_ns) + "): the log is out of order");
    }
    last_ns = t_ns;
    last_line = line;
  }
};

std::string string_field(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

}  // namespace

FlightRecord read_flight_record(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read the flight log '" + path + "'");
  return parse_flight_record(in, path);
}

FlightRecord parse_flight_record(std::istream& in, const std::string& name) {
  FlightRecord r;
  r.source = name;
  OrderCheck rc_order{"rc datagram"}, state_order{"state record"};
  TimeNs latest_ns = 0;  // the latest stamp so far, and its line
  int latest_line = 0;
  std::string text;
  bool ended = false;
  int n = 0;
  while (std::getline(in, text)) {
    ++n;
    const bool cut = in.eof();  // the last line has no newline: the writer stopped mid-line
    if (text.empty() && !cut) fail(name, n, "empty line: not a tello_pilot flight log (one JSON object per line)");
    if (text.empty()) break;
    json j = json::parse(text, nullptr, false);
    if (j.is_discarded()) {
      fail(name, n, cut ? "the last line is cut short (no complete JSON object): the log is truncated"
                        : "not a JSON object: not a tello_pilot flight log line");
    }
    if (!j.is_object() || !j.contains("t_ns") || !j["t_ns"].is_number_integer() || !j.contains("type") ||
        !j["type"].is_string()) {
      fail(name, n, "a JSON line without an integer \"t_ns\" and a string \"type\": not a tello_pilot flight log");
    }
    if (ended) fail(name, n, "a line after the 'end' line: two logs in one file?");
    const TimeNs t = j["t_ns"].get<TimeNs>();
    const std::string type = j["type"].get<std::string>();
    if (n == 1 && type != "start") fail(name, n, "the first line is '" + type + "', not 'start': not a tello_pilot flight log");
    if (n > 1 && type == "start") fail(name, n, "a second 'start' line: two logs in one file?");
    // Lines are written as the loop handles them: a driver event may be stamped a little before
    // a frame logged ahead of it, never by a second.
    if (latest_line > 0 && t + kNsPerSecond < latest_ns) {
      fail(name, n, "t = " + seconds_text(t) + " is more than a second before line " + std::to_string(latest_line) +
                        " (t = " + seconds_text(latest_ns) + "): the log is out of order");
    }
    if (t >= latest_ns) {
      latest_ns = t;
      latest_line = n;
    }
    if (type == "start") {
      r.start_ns = t;
      r.mode = string_field(j, "mode");
    } else if (type == "end") {
      r.end_ns = t;
      ended = true;
    } else if (type == "rc_sent" || type == "keepalive") {
      const std::string command = string_field(j, "command");
      const auto sticks = parse_rc(command);
      if (!sticks) fail(name, n, "'" + type + "' line with the command '" + command + "', not 'rc a b c d' in -100..100");
      rc_order.check(name, n, t);
      r.rc.push_back({t, *sticks});
    } else if (type == "state") {
      const std::string raw = string_field(j, "raw");
      const auto state = sdk::parse_state_record(raw, t);
      if (!state) fail(name, n, "a 'state' line whose raw record '" + raw + "' does not parse as a Tello state record");
      state_order.check(name, n, t);
      r.states.push_back(*state);
    } else if (type == "bad_state") {
      ++r.bad_states;
    } else if (type == "frame") {
      FrameStamps f;
      f.taken_ns = t;
      f.rx_ns = j.value("rx_ns", t);
      f.handed_ns = j.value("handed_ns", t);
      f.damaged = j.value("damaged", false);
      r.frames.push_back(f);
    } else if (type == "reply" && string_field(j, "command") == "takeoff" && string_field(j, "reply") == "ok") {
      if (!r.takeoff_ok_ns) r.takeoff_ok_ns = t;
    } else if (type == "stick_program" && string_field(j, "event") == "started") {
      if (!r.takeoff_ok_ns) r.takeoff_ok_ns = t;  // airborne, the takeoff's reply lost
    } else if (type == "sent" && string_field(j, "command") == "land") {
      if (r.takeoff_ok_ns && !r.land_sent_ns) r.land_sent_ns = t;
    }
  }
  r.lines = n;
  if (n == 0) throw FlightLogFormatError(name + ": empty: not a tello_pilot flight log");
  if (!ended) {
    fail(name, n, "no 'end' line after the last line (t = " + seconds_text(latest_ns) +
                      "): the log is truncated (the program was killed or the file cut)");
  }
  return r;
}

std::vector<TimeNs> state_send_times(const FlightRecord& r) {
  std::vector<TimeNs> t(r.states.size());
  for (size_t i = 0; i < t.size(); ++i) t[i] = r.states[i].t_ns;
  std::vector<double> periods;
  for (size_t i = 1; i < t.size(); ++i) {
    if (t[i] > t[i - 1]) periods.push_back(static_cast<double>(t[i] - t[i - 1]));
  }
  if (periods.size() < 10) return t;
  // The median period (between the middle two of an even count).
  std::sort(periods.begin(), periods.end());
  const double pos = 0.5 * static_cast<double>(periods.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos)), hi = std::min(lo + 1, periods.size() - 1);
  const auto least_gap = static_cast<TimeNs>(periods[lo] + (pos - static_cast<double>(lo)) * (periods[hi] - periods[lo]));
  for (size_t i = t.size() - 1; i-- > 0;) t[i] = std::min(t[i], t[i + 1] - least_gap);
  return t;
}

}  // namespace shelfcross::identify

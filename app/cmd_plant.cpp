// `shelfcross plant`: fly the simulated Tello (plant + onboard autopilot) open loop from a file
// of timed SDK commands, or the bare plant from a file of timed rotor speeds, and write the
// trajectory as CSV.

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "command_registry.hpp"
#include "plant/dynamics.hpp"
#include "plant/quadrotor.hpp"
#include "plant/simulated_tello.hpp"
#include "sdk/command.hpp"

namespace shelfcross::app {
namespace {

using namespace shelfcross::plant;

constexpr const char* kFootnote = R"(
Command file (--commands): one timed SDK command per line, `<t_seconds> <command>`, times
strictly increasing; blank lines and `#` comments allowed. The simulated firmware needs
`command` first (SDK mode), like a real Tello. Example:
  0    command
  0.5  takeoff
  6    rc 0 50 0 0      # a right, b forward, c up, d clockwise (each -100..100)
  9    rc 0 0 0 0
  12   land
Rotor file (--rotor-speeds): `<t_seconds> w1 w2 w3 w4` in rad/s (0..max), held until the next
line; the autopilot is bypassed.
Rotors, seen from above (x forward, y left, z up): 1 front-left (ccw), 2 front-right (cw),
3 rear-right (ccw), 4 rear-left (cw). Roll torque b a_y (w1^2 - w2^2 - w3^2 + w4^2), pitch
torque b a_x (-w1^2 - w2^2 + w3^2 + w4^2) (pitch > 0 lowers the nose), yaw torque
d (-w1^2 + w2^2 - w3^2 + w4^2) (yaw > 0 turns left).
CSV columns: t_s, position x_m y_m z_m and velocity vx_mps vy_mps vz_mps in the world frame
(x forward, y left, z up, origin on the floor), roll_rad pitch_rad yaw_rad (ZYX Euler of
R_WB; roll > 0 lowers the right side, pitch > 0 lowers the nose, yaw > 0 turns left), body
rates p_radps q_radps r_radps, rotor speeds w1..w4_radps. Autopilot replies go to stderr
(or --replies FILE) as `<t_s> <reply>`. Every command the firmware ignored (no effect, no
reply: before `command`, `rc` unless flying free) or refused (answered `error`: `takeoff`
unless landed, a move while landed or during another manoeuvre, ...) is printed with its time
and the reason, on stderr even with --replies; so is a landing by the 15 s watchdog.)";

struct PlantOptions {
  std::string commands_file;
  std::string rotor_file;
  double seconds = 0.0;
  std::string out_file;
  int rate_hz = 100;
  std::string replies_file;
};

struct TimedCommand {
  TimeNs t_ns;
  std::string text;
  int line;
};

struct TimedRotors {
  TimeNs t_ns;
  Eigen::Vector4d w_radps;
};

[[noreturn]] void bad_line(const std::string& file, int line, const std::string& reason) {
  throw UsageError(file + ":" + std::to_string(line) + ": " + reason);
}

// Splits "<t> rest" off a line; returns nullopt for blank/comment lines.
std::optional<std::pair<double, std::string>> split_timed_line(const std::string& file, int n, std::string line) {
  if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::istringstream is(line);
  std::string t_text;
  if (!(is >> t_text)) return std::nullopt;
  std::size_t used = 0;
  double t = 0.0;
  try {
    t = std::stod(t_text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != t_text.size() || !std::isfinite(t)) bad_line(file, n, "time '" + t_text + "' is not a number");
  if (t < 0.0) bad_line(file, n, "time " + t_text + " is negative");
  std::string rest;
  std::getline(is, rest);
  const auto first = rest.find_first_not_of(" \t");
  rest = first == std::string::npos ? "" : rest.substr(first);
  while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\t')) rest.pop_back();
  return std::make_pair(t, rest);
}

std::ifstream open_input(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw UsageError(file + ": cannot open file");
  return in;
}

std::vector<TimedCommand> read_commands(const std::string& file) {
  std::ifstream in = open_input(file);
  std::vector<TimedCommand> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto timed = split_timed_line(file, n, line);
    if (!timed) continue;
    const auto& [t, text] = *timed;
    if (text.empty()) bad_line(file, n, "missing command after the time");
    const TimeNs t_ns = seconds_to_ns(t);
    if (!out.empty() && t_ns <= out.back().t_ns)
      bad_line(file, n, "time " + std::to_string(t) + " s is not after the previous line's");
    const auto parsed = sdk::parse(text);
    if (const auto* err = std::get_if<sdk::ParseError>(&parsed))
      bad_line(file, n, err->reason + " (the Tello answers \"" + err->reply + "\")");
    out.push_back({t_ns, text, n});
  }
  return out;
}

std::vector<TimedRotors> read_rotors(const std::string& file, double w_max) {
  std::ifstream in = open_input(file);
  std::vector<TimedRotors> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto timed = split_timed_line(file, n, line);
    if (!timed) continue;
    const auto& [t, rest] = *timed;
    std::istringstream is(rest);
    Eigen::Vector4d w;
    for (int i = 0; i < 4; ++i) {
      std::string tok;
      if (!(is >> tok)) bad_line(file, n, "expected 4 rotor speeds after the time, got " + std::to_string(i));
      std::size_t used = 0;
      try {
        w[i] = std::stod(tok, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != tok.size() || !std::isfinite(w[i])) bad_line(file, n, "rotor speed '" + tok + "' is not a number");
      if (w[i] < 0.0 || w[i] > w_max)
        bad_line(file, n, "rotor speed " + tok + " rad/s is outside 0.." + std::to_string(w_max));
    }
    std::string extra;
    if (is >> extra) bad_line(file, n, "unexpected '" + extra + "' after 4 rotor speeds");
    const TimeNs t_ns = seconds_to_ns(t);
    if (!out.empty() && t_ns <= out.back().t_ns)
      bad_line(file, n, "time " + std::to_string(t) + " s is not after the previous line's");
    out.push_back({t_ns, w});
  }
  return out;
}

void write_row(std::ostream& os, TimeNs t_ns, const RigidBodyState& s) {
  const Eigen::Vector3d rpy = euler_zyx_from_quaternion(s.q_WB);
  os << ns_to_seconds(t_ns);
  for (int i = 0; i < 3; ++i) os << ',' << s.p_WB_m[i];
  for (int i = 0; i < 3; ++i) os << ',' << s.v_WB_W_mps[i];
  for (int i = 0; i < 3; ++i) os << ',' << rpy[i];
  for (int i = 0; i < 3; ++i) os << ',' << s.w_WB_B_radps[i];
  for (int i = 0; i < 4; ++i) os << ',' << s.rotor_speed_radps[i];
  os << '\n';
}

int run(const PlantOptions& o) {
  if (o.commands_file.empty() == o.rotor_file.empty())
    throw UsageError("plant: give exactly one of --commands FILE and --rotor-speeds FILE");
  if (!(o.seconds > 0.0) || !std::isfinite(o.seconds)) throw UsageError("plant: --seconds must be > 0");
  if (o.rate_hz <= 0) throw UsageError("plant: --rate must be a positive integer");

  const VehicleParams vehicle;
  const AutopilotParams autopilot;
  const WindParams wind;
  const TimeNs t_end = seconds_to_ns(o.seconds);

  std::vector<TimedCommand> commands;
  std::vector<TimedRotors> rotors;
  if (!o.commands_file.empty()) commands = read_commands(o.commands_file);
  else rotors = read_rotors(o.rotor_file, vehicle.rotor_speed_max_radps);

  std::ofstream out(o.out_file);
  if (!out) throw UsageError(o.out_file + ": cannot open for writing");
  out << std::setprecision(9);
  out << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,roll_rad,pitch_rad,yaw_rad,p_radps,q_radps,r_radps,"
         "w1_radps,w2_radps,w3_radps,w4_radps\n";

  std::ofstream replies_out;
  if (!o.replies_file.empty()) {
    replies_out.open(o.replies_file);
    if (!replies_out) throw UsageError(o.replies_file + ": cannot open for writing");
  }
  std::ostream& log = o.replies_file.empty() ? std::cerr : replies_out;
  const auto log_reply = [&](TimeNs t, const std::string& what) { log << ns_to_seconds(t) << ' ' << what << '\n'; };
  // What the firmware ignored or refused goes to the replies and, when they go to a file, to
  // stderr as well: a command file that flies nothing must say why.
  int refused = 0;
  const auto log_notice = [&](TimeNs t, const std::string& what) {
    log_reply(t, what);
    if (!o.replies_file.empty()) std::cerr << ns_to_seconds(t) << ' ' << what << '\n';
  };

  const std::int64_t n_samples = t_end * o.rate_hz / kNsPerSecond;  // samples k = 0..n_samples
  if (!o.commands_file.empty()) {
    SimulatedTello tello(vehicle, autopilot, wind, 0);
    std::size_t next = 0;
    TimeNs last_command_ns = 0;
    // The firmware's watchdog: flying with no command for watchdog_s, it lands by itself.
    const auto step_to = [&](TimeNs t) {
      const FlightMode before = tello.mode();
      tello.step_to(t);
      if ((before == FlightMode::taking_off || before == FlightMode::flying) && tello.mode() == FlightMode::landing) {
        std::ostringstream why;
        why << "landing by itself: no command for " << autopilot.watchdog_s << " s (since "
            << ns_to_seconds(last_command_ns) << " s)";
        log_notice(t, why.str());
      }
    };
    for (std::int64_t k = 0; k <= n_samples; ++k) {
      const TimeNs t_sample = tick_time_ns(k, o.rate_hz);
      while (next < commands.size() && commands[next].t_ns <= t_sample) {
        const auto& c = commands[next++];
        step_to(c.t_ns);
        const auto reply = tello.submit(c.t_ns, c.text);
        last_command_ns = c.t_ns;
        const std::string& why = tello.autopilot().last_refusal();
        if (!why.empty()) {
          ++refused;
          log_notice(c.t_ns, "\"" + c.text + "\" " + (reply ? "-> " + *reply + ": " : "") + why);
        } else if (reply) {
          log_reply(c.t_ns, "\"" + c.text + "\" -> " + *reply);
        }
        for (const auto& r : tello.take_replies()) log_reply(r.t_ns, "(deferred) -> " + r.text);
      }
      step_to(t_sample);
      for (const auto& r : tello.take_replies()) log_reply(r.t_ns, "(deferred) -> " + r.text);
      write_row(out, t_sample, tello.state());
    }
    log_reply(tello.time_ns(), "final mode: " + std::string(to_string(tello.mode())));
    if (refused > 0) {
      std::cerr << refused << " of " << commands.size() << " commands ignored or refused by the simulated firmware"
                << " (listed above" << (o.replies_file.empty() ? "" : " and in " + o.replies_file) << ")\n";
    }
    return 0;
  }
  Quadrotor quad(vehicle, wind, 0);
  quad.reset(Quadrotor::landed_state(vehicle), 0);
  std::size_t next = 0;
  for (std::int64_t k = 0; k <= n_samples; ++k) {
    const TimeNs t_sample = tick_time_ns(k, o.rate_hz);
    while (next < rotors.size() && rotors[next].t_ns <= t_sample) {
      quad.advance_to(rotors[next].t_ns);
      quad.set_rotor_commands(rotors[next].w_radps);
      ++next;
    }
    quad.advance_to(t_sample);
    write_row(out, t_sample, quad.state());
  }
  return 0;
}

const CommandRegistration reg{
    "plant", "Fly the simulated Tello (plant + onboard autopilot) open loop and write its trajectory as CSV",
    [](CLI::App& sub) -> CommandAction {
      auto o = std::make_shared<PlantOptions>();
      auto* cmds = sub.add_option("--commands", o->commands_file, "File of timed SDK commands: `<t_s> <command>` per line");
      auto* rot = sub.add_option("--rotor-speeds", o->rotor_file,
                                 "File of timed rotor speeds: `<t_s> w1 w2 w3 w4` (rad/s) per line; bypasses the autopilot");
      cmds->excludes(rot);
      sub.add_option("--seconds", o->seconds, "Simulated duration (s)")->required();
      sub.add_option("--out", o->out_file, "Output CSV file")->required();
      sub.add_option("--rate", o->rate_hz, "CSV sample rate (Hz, integer)")->capture_default_str();
      sub.add_option("--replies", o->replies_file, "Write the autopilot's replies here instead of stderr");
      sub.footer(kFootnote);
      return [o]() { return run(*o); };
    }};

}  // namespace
}  // namespace shelfcross::app

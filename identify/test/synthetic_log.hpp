#pragma once
// Synthetic tello_pilot flight logs with a known response: the calibration manoeuvre's sticks,
// sent as tello_pilot's driver sends them (a new setpoint at once, repeats every 100 ms), and
// state records at 10 Hz of the response model of identify/response_fit.hpp (the reference
// model tracked by the simulated autopilot's loops, plant defaults) with known gains, time
// constants and dead time, plus Gaussian noise from a fixed seed, written by the simulated
// Tello's own state formatter (the SDK's integer dm/s, cm and degrees).

#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "flight_sw/tello/calibration_manoeuvre.hpp"
#include "identify/identification.hpp"
#include "identify/response_fit.hpp"
#include "plant/params.hpp"
#include "sdk/command.hpp"
#include "shelfcross/random.hpp"
#include "shelfcross/rotation.hpp"
#include "verification/world/tello_state_format.hpp"

namespace shelfcross::identify::testing {

struct KnownDrone {
  // forward, lateral, vertical, yaw
  std::array<double, 4> gain = {1.0, 1.0, 1.0, 1.5};
  std::array<double, 4> tau_s = {0.5, 0.5, 0.4, 0.3};
  double delay_s = 0.12;
  double velocity_noise_mps = 0.03;  ///< per record, before the SDK's 0.1 m/s rounding
  double height_noise_m = 0.01;
  double yaw_noise_rad = 0.005;
  std::uint64_t seed = 7;
  bool excite_lateral = true;
};

inline std::string log_line(TimeNs t_ns, const std::string& type, nlohmann::json fields = nlohmann::json::object()) {
  nlohmann::ordered_json j;
  j["t_s"] = ns_to_seconds(t_ns);
  j["t_ns"] = t_ns;
  j["type"] = type;
  for (auto& [k, v] : fields.items()) j[k] = v;
  return j.dump() + "\n";
}

/// The whole log: start, takeoff ok, the manoeuvre (rc lines), state lines, land, end.
inline std::string synthetic_log(const KnownDrone& drone) {
  const tello::CalibrationManoeuvre manoeuvre;
  const TimeNs t_takeoff = 5 * kNsPerSecond;
  const TimeNs t_program = t_takeoff + kNsPerSecond / 20;
  const TimeNs t_land = t_program + seconds_to_ns(manoeuvre.duration_s()) + kNsPerSecond;
  // The rc datagrams: each new setpoint at once, repeats every 100 ms (times in ms steps).
  std::vector<std::pair<TimeNs, std::array<int, 4>>> rc;
  std::array<int, 4> sent{};
  for (TimeNs t = t_program; t <= t_land; t += kNsPerSecond / 1000) {
    const tello::ManoeuvreStep* s = manoeuvre.step_at(ns_to_seconds(t - t_program));
    std::array<int, 4> wanted = s ? s->sticks : std::array<int, 4>{};
    if (!drone.excite_lateral) wanted[0] = 0;
    if (rc.empty() || wanted != sent || t - rc.back().first >= kNsPerSecond / 10) {
      sent = wanted;
      rc.push_back({t, sent});
    }
  }
  // The responses at the state records' times, per axis, through the plant's default loops.
  std::vector<double> t_s;
  for (TimeNs t = t_takeoff; t <= t_land; t += kNsPerSecond / 10) t_s.push_back(ns_to_seconds(t - t_takeoff));
  std::array<std::vector<double>, 4> y;
  const plant::AutopilotParams autopilot;
  const plant::VehicleParams vehicle;
  for (size_t i = 0; i < kAxes.size(); ++i) {
    const Axis axis = kAxes[i];
    const int stick = axis == Axis::forward ? 1 : axis == Axis::lateral ? 0 : axis == Axis::vertical ? 2 : 3;
    const double sign = axis == Axis::lateral || axis == Axis::yaw ? -1.0 : 1.0;
    PiecewiseInput input;
    for (const auto& [t, sticks] : rc) {
      input.t_s.push_back(ns_to_seconds(t - t_takeoff));
      input.u.push_back(sign * sticks[static_cast<size_t>(stick)] / 100.0);
    }
    const Observation obs = axis == Axis::vertical || axis == Axis::yaw ? Observation::integral : Observation::direct;
    y[i] = unit_response(input, drone.tau_s[i], drone.delay_s, t_s, obs, tracking_loop(axis, autopilot, vehicle));
    for (double& v : y[i]) v *= drone.gain[i];
  }
  RandomStream noise(drone.seed, StreamId::sensor_noise);
  std::ostringstream log;
  log << log_line(0, "start", {{"mode", "calibration_flight"}});
  log << log_line(t_takeoff, "reply", {{"command", "takeoff"}, {"reply", "ok"}});
  size_t next_rc = 0;
  for (size_t k = 0; k < t_s.size(); ++k) {
    const TimeNs t = t_takeoff + seconds_to_ns(t_s[k]);
    for (; next_rc < rc.size() && rc[next_rc].first <= t; ++next_rc) {
      const auto& s = rc[next_rc].second;
      log << log_line(rc[next_rc].first, "rc_sent", {{"command", sdk::rc_text(s[0], s[1], s[2], s[3])}});
    }
    StateRecord r;
    r.vx_H_mps = y[0][k] + noise.normal(0.0, drone.velocity_noise_mps);
    r.vy_H_mps = y[1][k] + noise.normal(0.0, drone.velocity_noise_mps);
    r.height_m = 1.0 + y[2][k] + noise.normal(0.0, drone.height_noise_m);
    r.yaw_rad = shelfcross::wrap_pi(0.3 + y[3][k] + noise.normal(0.0, drone.yaw_noise_rad));
    r.battery_pct = 80;
    r.tof_m = r.height_m + 0.1;
    r.az_B_mps2 = 9.81;
    log << log_line(t, "state", {{"raw", verification::format_state_record(r)}, {"battery_pct", 80}, {"height_m", r.height_m}});
  }
  log << log_line(t_land, "sent", {{"command", "land"}, {"attempt", 1}, {"origin", "pilot"}});
  log << log_line(t_land + 2 * kNsPerSecond, "end", {{"exit_code", 0}});
  return log.str();
}

}  // namespace shelfcross::identify::testing

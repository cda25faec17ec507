#pragma once
// Synthetic tello_pilot flight logs with a known response: the calibration manoeuvre's sticks,
// sent as tello_pilot's driver sends them (a new setpoint at once, repeats every 100 ms), and
// state records at 10 Hz of the response model of identify/response_fit.hpp (the reference
// model tracked by the simulated autopilot's loops, plant defaults) with known gains, time
// constants and dead time, plus Gaussian noise from a fixed seed, written by the simulated
// Tello's own state formatter (the SDK's integer dm/s, cm and degrees).
// With KnownSenses, the manoeuvre flies its senses block too, and the records carry the senses
// of plant/tello_senses.hpp, simulated directly at 50 Hz: the board behind the take-off point
// under the forward response's path; the hold's range offset o following -beta (S + d + tof
// noise) with its time constant; the barometer's drift d; the height hold's correction of z
// (first order, 0.5 s) and a slow wander of the air (AR(1), 1 s) in height and velocity; then
// h = z + d + o + noise, tof = 0.1 + z - S + noise, baro = 100 + z + d + noise, vgx and vgy the
// response plus the wander plus the VPS's noise.

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
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

struct KnownSenses {
  double board_distance_m = 1.5;     ///< its middle, straight behind the take-off point
  double board_half_length_m = 0.6;  ///< along the path
  double board_height_m = 0.29;
  bool board_on_path = true;         ///< false: the board lies elsewhere, never passed over
  double vps_noise_mps = 0.03, height_noise_m = 0.01, baro_noise_m = 0.05, tof_noise_m = 0.01;
  double range_blend = 0.5, hold_time_constant_s = 0.6;
  double baro_drift_m_per_sqrt_s = 0.005;
  double wander_m = 0.004, wander_mps = 0.01;  ///< the air's, stationary standard deviations
};

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
  std::optional<KnownSenses> senses;
};

/// The senses' readings at the state records (KnownSenses above), per record: h, tof, baro and
/// the two velocity wanders with the VPS's noise.
struct SensedRecords {
  std::vector<double> h_m, tof_m, baro_m, dvx_mps, dvy_mps;
};

inline SensedRecords simulate_senses(const KnownSenses& k, const std::vector<double>& forward_position_m,
                                     const std::vector<double>& height_m, std::uint64_t seed) {
  // forward_position_m and height_m at 50 Hz (every record is each fifth sample).
  constexpr double dt = 0.02;
  RandomStream rng(seed, StreamId::height_sensors);
  const double a_tau = -std::expm1(-dt / k.hold_time_constant_s), a_hold = -std::expm1(-dt / 0.5);
  const double a_air = std::exp(-dt / 1.0), kick = std::sqrt(1.0 - a_air * a_air);
  double d = 0.0, o = 0.0, c = 0.0, wz = 0.0, wx = 0.0, wy = 0.0;
  SensedRecords out;
  for (size_t i = 0; i < forward_position_m.size(); ++i) {
    const double x = forward_position_m[i];
    const bool over = k.board_on_path && std::abs(x + k.board_distance_m) <= k.board_half_length_m;
    const double S = over ? k.board_height_m : 0.0;
    const double n_tof = rng.normal(0.0, k.tof_noise_m);
    d += k.baro_drift_m_per_sqrt_s * std::sqrt(dt) * rng.normal();
    o += (-k.range_blend * (S + d - n_tof) - o) * a_tau;
    c += (-(d + o) - c) * a_hold;
    wz = a_air * wz + kick * k.wander_m * rng.normal();
    wx = a_air * wx + kick * k.wander_mps * rng.normal();
    wy = a_air * wy + kick * k.wander_mps * rng.normal();
    const double n_h = rng.normal(0.0, k.height_noise_m), n_b = rng.normal(0.0, k.baro_noise_m);
    const double n_vx = rng.normal(0.0, k.vps_noise_mps), n_vy = rng.normal(0.0, k.vps_noise_mps);
    if (i % 5 != 0) continue;
    const double z = height_m[i] + c + wz;
    out.h_m.push_back(z + d + o + n_h);
    out.tof_m.push_back(0.1 + z - S + n_tof);
    out.baro_m.push_back(100.0 + z + d + n_b);
    out.dvx_mps.push_back(wx + n_vx);
    out.dvy_mps.push_back(wy + n_vy);
  }
  return out;
}

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
  const tello::CalibrationManoeuvre manoeuvre(
      tello::CalibrationAmplitudes{},
      drone.senses ? std::optional(tello::CalibrationSenses{drone.senses->board_distance_m}) : std::nullopt);
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
  std::optional<SensedRecords> sensed;
  if (drone.senses) {
    // The forward position and the height at 50 Hz, for the board and the hold.
    std::vector<double> t50;
    for (size_t k = 0; k < t_s.size(); ++k) {
      for (int j = 0; j < 5; ++j) t50.push_back(t_s[k] + 0.02 * j);
    }
    PiecewiseInput forward, up;
    for (const auto& [t, sticks] : rc) {
      forward.t_s.push_back(ns_to_seconds(t - t_takeoff));
      forward.u.push_back(sticks[1] / 100.0);
      up.t_s.push_back(forward.t_s.back());
      up.u.push_back(sticks[2] / 100.0);
    }
    std::vector<double> x = unit_response(forward, drone.tau_s[0], drone.delay_s, t50, Observation::integral,
                                          tracking_loop(Axis::forward, autopilot, vehicle));
    std::vector<double> z = unit_response(up, drone.tau_s[2], drone.delay_s, t50, Observation::integral,
                                          tracking_loop(Axis::vertical, autopilot, vehicle));
    for (double& v : x) v *= drone.gain[0];
    for (double& v : z) v = 1.0 + v * drone.gain[2];
    sensed = simulate_senses(*drone.senses, x, z, drone.seed);
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
    if (sensed) {
      r.vx_H_mps = y[0][k] + sensed->dvx_mps[k];
      r.vy_H_mps = y[1][k] + sensed->dvy_mps[k];
      r.height_m = sensed->h_m[k];
      r.tof_m = sensed->tof_m[k];
      r.baro_m = sensed->baro_m[k];
    }
    r.az_B_mps2 = 9.81;
    log << log_line(t, "state", {{"raw", verification::format_state_record(r)}, {"battery_pct", 80}, {"height_m", r.height_m}});
  }
  log << log_line(t_land, "sent", {{"command", "land"}, {"attempt", 1}, {"origin", "pilot"}});
  log << log_line(t_land + 2 * kNsPerSecond, "end", {{"exit_code", 0}});
  return log.str();
}

/// The flight record a log's text parses to (as if read from "flight.jsonl").
inline FlightRecord record_of(const std::string& text) {
  std::istringstream in(text);
  return parse_flight_record(in, "flight.jsonl");
}

}  // namespace shelfcross::identify::testing

#include "plant/flight_modes.hpp"

#include <algorithm>
#include <cmath>

#include "shelfcross/rotation.hpp"

namespace shelfcross::plant {
namespace {

Eigen::Vector3d heading_to_world(double yaw, const Eigen::Vector3d& v_H) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * v_H.x() - s * v_H.y(), s * v_H.x() + c * v_H.y(), v_H.z()};
}

/// The references at rest where the firmware senses the drone: position and velocity from the
/// estimate, the yaw from the IMU.
void capture(FlightReferences& ref, const SensedState& sensed, const Eigen::Quaterniond& q_WB) {
  ref.p_W_m = sensed.p_W_m;
  ref.v_W_mps = sensed.v_W_mps;
  ref.a_ff_W_mps2.setZero();
  ref.yaw_rad = euler_zyx_from_quaternion(q_WB).z();
  ref.yaw_rate_radps = 0.0;
}

/// Free flight on the sticks (a b c d): velocity commands in the heading frame, each through a
/// first-order reference model, integrated into the position and yaw references.
void rc_references(const AutopilotParams& P, const std::array<int, 4>& sticks, double dt, double yaw,
                   FlightReferences& ref) {
  const double vh = P.rc_horizontal_mps_at_100 * (P.fast_mode ? P.fast_mode_speed_factor : 1.0);
  const Eigen::Vector3d v_H(sticks[1] / 100.0 * vh, -sticks[0] / 100.0 * vh,
                            sticks[2] / 100.0 * P.rc_vertical_mps_at_100);
  const Eigen::Vector3d v_cmd = heading_to_world(yaw, v_H);
  const double r_cmd = -sticks[3] / 100.0 * P.rc_yaw_radps_at_100;
  // First-order reference models, discretised exactly for the tick: x += (u - x)(1 - e^{-dt/tau}).
  const double th = P.velocity_time_constant_s, tz = P.vertical_time_constant_s;
  const Eigen::Vector3d tau(th, th, tz);
  for (int i = 0; i < 3; ++i) {
    ref.a_ff_W_mps2[i] = (v_cmd[i] - ref.v_W_mps[i]) / tau[i];
    ref.v_W_mps[i] += (v_cmd[i] - ref.v_W_mps[i]) * -std::expm1(-dt / tau[i]);
  }
  ref.yaw_rate_radps += (r_cmd - ref.yaw_rate_radps) * -std::expm1(-dt / P.yaw_time_constant_s);
  ref.p_W_m += ref.v_W_mps * dt;
  ref.yaw_rad += ref.yaw_rate_radps * dt;
}

}  // namespace

std::string_view to_string(FlightMode mode) {
  switch (mode) {
    case FlightMode::landed: return "landed";
    case FlightMode::taking_off: return "taking_off";
    case FlightMode::flying: return "flying";
    case FlightMode::landing: return "landing";
    case FlightMode::emergency: return "emergency";
  }
  return "?";
}

FlightModes::FlightModes(const AutopilotParams& params, const VehicleParams& vehicle)
    : params_(params), vehicle_(vehicle), takeoff_z_m_(vehicle.floor_z_m + vehicle.rest_height_m()) {}

std::vector<SdkReply> FlightModes::take_replies() {
  std::vector<SdkReply> out;
  out.swap(replies_);
  return out;
}

void FlightModes::take_off(TimeNs t_ns, const SensedState& sensed, const Eigen::Quaterniond& q_WB) {
  mode_ = FlightMode::taking_off;
  phase_.start_ns = t_ns;
  phase_.settled_since_ns.reset();
  phase_.reply_takeoff = true;
  sticks_ = {};
  takeoff_z_m_ = sensed.p_W_m.z();
  capture(ref_, sensed, q_WB);
}

void FlightModes::start_landing(bool reply_when_done) {
  if (manoeuvre_.active) manoeuvre_.active = false;  // its reply is dropped
  phase_.reply_takeoff = false;
  phase_.reply_land = reply_when_done;
  mode_ = FlightMode::landing;
  sticks_ = {};
}

void FlightModes::emergency() {
  manoeuvre_.active = false;
  phase_.reply_takeoff = phase_.reply_land = false;
  mode_ = FlightMode::emergency;
}

void FlightModes::stop(const SensedState& sensed, const Eigen::Quaterniond& q_WB) {
  manoeuvre_.active = false;
  sticks_ = {};
  capture(ref_, sensed, q_WB);
}

void FlightModes::start_move(sdk::Verb verb, const Eigen::Vector3d& delta_H_m, double dyaw_rad, double speed_mps,
                             const SensedState& sensed, const Eigen::Quaterniond& q_WB) {
  const double yaw = euler_zyx_from_quaternion(q_WB).z();
  sticks_ = {};
  capture(ref_, sensed, q_WB);
  manoeuvre_ = {true, verb, ref_.p_W_m + heading_to_world(yaw, delta_H_m), ref_.yaw_rad + dyaw_rad, speed_mps};
}

void FlightModes::manoeuvre_references(TimeNs t_ns, double dt, const RigidBodyState& s, const SensedState& sensed) {
  Manoeuvre& m = manoeuvre_;
  FlightReferences& r = ref_;
  const Eigen::Vector3d to_go = m.target_W_m - r.p_W_m;
  const double dist = to_go.norm();
  const double step = m.speed_mps * dt;
  r.a_ff_W_mps2.setZero();
  if (dist > step) {
    r.v_W_mps = to_go / dist * m.speed_mps;
    r.p_W_m += r.v_W_mps * dt;
  } else {
    r.p_W_m = m.target_W_m;
    r.v_W_mps.setZero();
  }
  const double yaw_to_go = m.target_yaw_rad - r.yaw_rad;
  const double yaw_step = params_.rc_yaw_radps_at_100 * dt;
  if (std::abs(yaw_to_go) > yaw_step) {
    r.yaw_rate_radps = std::copysign(params_.rc_yaw_radps_at_100, yaw_to_go);
    r.yaw_rad += r.yaw_rate_radps * dt;
  } else {
    r.yaw_rad = m.target_yaw_rad;
    r.yaw_rate_radps = 0.0;
  }
  // Settled as the firmware judges it: on its estimate and its IMU.
  const double yaw = euler_zyx_from_quaternion(s.q_WB).z();
  const bool settled = r.p_W_m == m.target_W_m && r.yaw_rad == m.target_yaw_rad &&
                       (sensed.p_W_m - m.target_W_m).norm() < 0.10 && sensed.v_W_mps.norm() < 0.15 &&
                       std::abs(wrap_pi(yaw - m.target_yaw_rad)) < 0.05 && s.w_WB_B_radps.norm() < 0.2;
  if (settled) {
    m.active = false;
    replies_.push_back({t_ns, "ok"});
  }
}

Drive FlightModes::take_off_tick(TimeNs t_ns, double dt, const SensedState& sensed, bool on_ground) {
  FlightReferences& r = ref_;
  const double z_target = vehicle_.floor_z_m + params_.takeoff_height_m;
  // Climb at takeoff_climb_mps, easing into the target height: the reference speed is
  // min(climb, remaining / 0.3 s), changing at most 1 m/s^2; p_ref integrates it exactly.
  // While still on the floor the reference waits for the vehicle (no lead to catch up on).
  if (on_ground) r.p_W_m.z() = sensed.p_W_m.z();
  const double remaining = z_target - r.p_W_m.z();
  r.a_ff_W_mps2.setZero();
  r.v_W_mps.head<2>().setZero();
  if (remaining > 2e-3) {
    const double vz_target = std::min(params_.takeoff_climb_mps, remaining / 0.3);
    const double dv = std::clamp(vz_target - r.v_W_mps.z(), -1.0 * dt, 1.0 * dt);
    r.v_W_mps.z() += dv;
    r.a_ff_W_mps2.z() = dt > 0.0 ? dv / dt : 0.0;
    r.p_W_m.z() += r.v_W_mps.z() * dt;
  } else {
    r.p_W_m.z() = z_target;
    r.v_W_mps.z() = 0.0;
  }
  const bool settled = z_target - r.p_W_m.z() < 0.02 && std::abs(sensed.p_W_m.z() - z_target) < 0.03 &&
                       sensed.v_W_mps.norm() < 0.1;
  if (settled && !phase_.settled_since_ns) phase_.settled_since_ns = t_ns;
  if (phase_.settled_since_ns && t_ns - *phase_.settled_since_ns >= seconds_to_ns(params_.takeoff_reply_delay_s)) {
    mode_ = FlightMode::flying;
    if (phase_.reply_takeoff) replies_.push_back({t_ns, "ok"});
    phase_.reply_takeoff = false;
  }
  return Drive::fly;
}

Drive FlightModes::tick(TimeNs t_ns, double dt, const RigidBodyState& s, const SensedState& sensed, bool on_ground) {
  switch (mode_) {
    case FlightMode::landed:
      return Drive::motors_off;
    case FlightMode::emergency:
      if (on_ground && s.v_WB_W_mps.norm() < 1e-6) mode_ = FlightMode::landed;
      return Drive::motors_off;
    case FlightMode::taking_off:
      if (t_ns - phase_.start_ns < seconds_to_ns(params_.takeoff_spinup_s)) {
        capture(ref_, sensed, s.q_WB);
        return Drive::idle;
      }
      return take_off_tick(t_ns, dt, sensed, on_ground);
    case FlightMode::flying:
      if (manoeuvre_.active) {
        manoeuvre_references(t_ns, dt, s, sensed);
      } else {
        rc_references(params_, sticks_, dt, euler_zyx_from_quaternion(s.q_WB).z(), ref_);
      }
      return Drive::fly;
    case FlightMode::landing:
      if (on_ground) {
        mode_ = FlightMode::landed;
        if (phase_.reply_land) replies_.push_back({t_ns, "ok"});
        phase_.reply_land = false;
        return Drive::motors_off;
      }
      // Descend at land_speed_mps; the reference may go below the floor so the vehicle
      // keeps settling onto it.
      ref_.v_W_mps = Eigen::Vector3d(0.0, 0.0, -params_.land_speed_mps);
      ref_.a_ff_W_mps2.setZero();
      ref_.p_W_m.z() = std::max(ref_.p_W_m.z() - params_.land_speed_mps * dt,
                                vehicle_.floor_z_m + vehicle_.rest_height_m() - 0.2);
      ref_.yaw_rate_radps = 0.0;
      return Drive::fly;
  }
  return Drive::motors_off;
}

}  // namespace shelfcross::plant

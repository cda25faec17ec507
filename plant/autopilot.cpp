#include "plant/autopilot.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shelfcross::plant {
namespace {

constexpr double kOnGroundTolerance_m = 0.003;  // the plant holds a resting vehicle exactly at z_rest

}  // namespace

Autopilot::Autopilot(const AutopilotParams& params, const VehicleParams& vehicle, TelloSenses senses)
    : params_(params),
      vehicle_(vehicle),
      senses_(std::move(senses)),
      sdk_(params.move_speed_default_mps),
      modes_(params, vehicle),
      controller_(params, vehicle) {
  const double r = params.rate_hz;
  if (!(r > 0.0) || r != std::floor(r) || r > 1e6) throw std::invalid_argument("autopilot: rate_hz must be a positive integer");
  const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!pos(params.velocity_time_constant_s) || !pos(params.vertical_time_constant_s) ||
      !pos(params.yaw_time_constant_s) || !pos(params.tilt_limit_slow_rad) || !pos(params.tilt_limit_fast_rad) ||
      params.tilt_limit_fast_rad >= 1.5 || !pos(params.takeoff_height_m) || !pos(params.land_speed_mps) ||
      !pos(params.watchdog_s) || !pos(params.takeoff_climb_mps) || !pos(params.position_leash_m) ||
      !pos(params.battery_endurance_s))
    throw std::invalid_argument("autopilot: time constants, limits, speeds must be positive");
}

int Autopilot::battery_pct() const {
  // The one battery of the simulated Tello: linear in motor-on time, read by `battery?` and
  // sent in every state record.
  const double used_pct = 100.0 * motor_on_time_s() / params_.battery_endurance_s;
  return static_cast<int>(std::clamp(std::floor(params_.battery_start_pct - used_pct), 0.0, 100.0));
}

DroneReadout Autopilot::readout() const {
  const SensedReadings r = senses_.readings(last_state_);
  DroneReadout d;
  d.sensed = sensed_;
  d.q_WB = last_state_.q_WB;
  d.battery_pct = battery_pct();
  d.motor_on_ns = motor_on_ns_;
  d.height_above_takeoff_m = r.height_W_m - modes_.takeoff_z_m();
  d.tof_m = r.tof_m;
  d.baro_m = r.baro_m;
  d.specific_force_B_mps2 = specific_force_B_;
  d.gravity_mps2 = vehicle_.gravity_mps2;
  return d;
}

std::optional<std::string> Autopilot::on_command(TimeNs t_ns, std::string_view text) {
  last_command_ns_ = t_ns;  // any datagram counts for the watchdog
  return sdk_.on_command(t_ns, text, modes_, readout());
}

Eigen::Vector4d Autopilot::update(TimeNs t_ns, const RigidBodyState& s) {
  double dt = 1.0 / params_.rate_hz;
  if (last_update_ns_) dt = std::clamp(ns_to_seconds(t_ns - *last_update_ns_), 0.0, 0.1);
  if (last_update_ns_ && dt > 0.0) {
    const Eigen::Vector3d a_W = (s.v_WB_W_mps - last_state_.v_WB_W_mps) / dt;
    specific_force_B_ = s.q_WB.conjugate() * (a_W + Eigen::Vector3d(0.0, 0.0, vehicle_.gravity_mps2));
  }
  last_update_ns_ = t_ns;
  last_state_ = s;
  sensed_ = senses_.sense(t_ns, s);
  const bool on_ground = s.p_WB_m.z() <= vehicle_.floor_z_m + vehicle_.rest_height_m() + kOnGroundTolerance_m;
  const FlightMode mode = modes_.mode();
  const bool motors_on = mode == FlightMode::taking_off || mode == FlightMode::flying || mode == FlightMode::landing;
  if (motors_on) motor_on_ns_ += seconds_to_ns(dt);

  // Watchdog: no command at all for watchdog_s while flying -> land by itself.
  if ((mode == FlightMode::taking_off || mode == FlightMode::flying) &&
      t_ns - last_command_ns_ >= seconds_to_ns(params_.watchdog_s))
    modes_.start_landing(false);

  switch (modes_.tick(t_ns, dt, s, sensed_, on_ground)) {
    case Drive::motors_off:
      controller_.reset_integrators();
      return Eigen::Vector4d::Zero();
    case Drive::idle:
      controller_.reset_integrators();
      return Eigen::Vector4d::Constant(vehicle_.rotor_speed_min_radps);
    case Drive::fly:
      break;
  }
  return controller_.control(dt, s, sensed_, modes_.references(), on_ground);
}

}  // namespace shelfcross::plant

#include "plant/autopilot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "shelfcross/rotation.hpp"

namespace shelfcross::plant {
namespace {

constexpr double kDegPerRad = 57.29577951308232;
constexpr double kOnGroundTolerance_m = 0.003;  // the plant holds a resting vehicle exactly at z_rest

Eigen::Vector3d heading_to_world(double yaw, const Eigen::Vector3d& v_H) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * v_H.x() - s * v_H.y(), s * v_H.x() + c * v_H.y(), v_H.z()};
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

Autopilot::Autopilot(const AutopilotParams& params, const VehicleParams& vehicle)
    : params_(params), vehicle_(vehicle), move_speed_mps_(params.move_speed_default_mps) {
  const double r = params.rate_hz;
  if (!(r > 0.0) || r != std::floor(r) || r > 1e6) throw std::invalid_argument("autopilot: rate_hz must be a positive integer");
  tick_ns_ = tick_time_ns(1, static_cast<std::int64_t>(r));
  const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!pos(params.velocity_time_constant_s) || !pos(params.vertical_time_constant_s) ||
      !pos(params.yaw_time_constant_s) || !pos(params.tilt_limit_slow_rad) || !pos(params.tilt_limit_fast_rad) ||
      params.tilt_limit_fast_rad >= 1.5 || !pos(params.takeoff_height_m) || !pos(params.land_speed_mps) ||
      !pos(params.watchdog_s) || !pos(params.takeoff_climb_mps) || !pos(params.position_leash_m) ||
      !pos(params.battery_endurance_s))
    throw std::invalid_argument("autopilot: time constants, limits, speeds must be positive");
  takeoff_z_m_ = rest_z();
}

double Autopilot::tilt_limit_rad() const {
  return params_.fast_mode ? params_.tilt_limit_fast_rad : params_.tilt_limit_slow_rad;
}

int Autopilot::battery_pct() const {
  // The one battery of the simulated Tello: linear in motor-on time, read by `battery?` and
  // sent in every state record.
  const double used_pct = 100.0 * motor_on_time_s() / params_.battery_endurance_s;
  return static_cast<int>(std::clamp(std::floor(params_.battery_start_pct - used_pct), 0.0, 100.0));
}

double Autopilot::height_above_takeoff_m() const { return last_state_.p_WB_m.z() - takeoff_z_m_; }

double Autopilot::tof_m() const { return 0.1 + last_state_.p_WB_m.z() - rest_z(); }

std::optional<std::string> Autopilot::on_command(TimeNs t_ns, std::string_view text) {
  last_command_ns_ = t_ns;  // any datagram counts for the watchdog
  last_refusal_.clear();
  const auto parsed = sdk::parse(text);
  if (const auto* err = std::get_if<sdk::ParseError>(&parsed)) {
    // rc is never answered, even when malformed; nothing is answered outside SDK mode.
    const bool is_rc = text.substr(0, 3) == "rc " || text == "rc";
    if (!sdk_mode_) {
      last_refusal_ = "ignored: not in SDK mode ('command' not received yet), no reply";
      return std::nullopt;
    }
    if (is_rc) return refuse("ignored: " + err->reason + ", no reply (rc is never answered)", std::nullopt);
    return refuse("refused: " + err->reason, err->reply);
  }
  const auto& c = std::get<sdk::Command>(parsed);
  if (!sdk_mode_ && c.verb != sdk::Verb::command) {
    last_refusal_ = "ignored: not in SDK mode ('command' not received yet), no reply";
    return std::nullopt;
  }
  return execute(t_ns, c);
}

std::optional<std::string> Autopilot::refuse(std::string why, std::optional<std::string> reply) {
  last_refusal_ = std::move(why);
  return reply;
}

std::string Autopilot::mode_text() const {
  if (mode_ == FlightMode::flying && manoeuvre_.active) return "a manoeuvre is running";
  return "the drone is " + std::string(to_string(mode_));
}

void Autopilot::start_landing(bool reply_when_done) {
  if (manoeuvre_.active) manoeuvre_.active = false;  // its reply is dropped
  reply_takeoff_ = false;
  reply_land_ = reply_when_done;
  mode_ = FlightMode::landing;
  sticks_ = {};
}

std::optional<std::string> Autopilot::execute(TimeNs t_ns, const sdk::Command& c) {
  using sdk::Verb;
  const bool airborne = mode_ == FlightMode::taking_off || mode_ == FlightMode::flying || mode_ == FlightMode::landing;
  const bool flying_free = mode_ == FlightMode::flying && !manoeuvre_.active;
  switch (c.verb) {
    case Verb::command:
      sdk_mode_ = true;
      return "ok";
    case Verb::takeoff:
      if (mode_ != FlightMode::landed) return refuse("refused: " + mode_text(), "error");
      if (battery_pct() < 10) {
        return refuse("refused: battery at " + std::to_string(battery_pct()) + " % (takeoff needs 10 %)", "error");
      }
      mode_ = FlightMode::taking_off;
      phase_start_ns_ = t_ns;
      settled_since_ns_.reset();
      reply_takeoff_ = true;
      sticks_ = {};
      takeoff_z_m_ = last_state_.p_WB_m.z();
      capture_references(last_state_);
      return std::nullopt;
    case Verb::land:
      if (mode_ != FlightMode::taking_off && mode_ != FlightMode::flying) {
        return refuse("refused: " + mode_text(), "error");
      }
      start_landing(true);
      return std::nullopt;
    case Verb::emergency:
      if (airborne) {
        manoeuvre_.active = false;
        reply_takeoff_ = reply_land_ = false;
        mode_ = FlightMode::emergency;
      }
      return "ok";
    case Verb::stop:
      if (mode_ != FlightMode::flying) return refuse("refused: " + mode_text(), "error");
      manoeuvre_.active = false;
      sticks_ = {};
      capture_references(last_state_);
      return "ok";
    case Verb::streamon:
      stream_on_ = true;
      return "ok";
    case Verb::streamoff:
      stream_on_ = false;
      return "ok";
    case Verb::speed:
      move_speed_mps_ = c.args[0] / 100.0;
      return "ok";
    case Verb::rc:
      if (!flying_free) {
        return refuse("ignored: " + mode_text() + " (rc acts only while flying free), no reply", std::nullopt);
      }
      sticks_ = {c.args[0], c.args[1], c.args[2], c.args[3]};
      return std::nullopt;
    case Verb::up: case Verb::down: case Verb::left: case Verb::right: case Verb::forward: case Verb::back:
    case Verb::cw: case Verb::ccw: case Verb::go: {
      if (!flying_free) return refuse("refused: " + mode_text(), "error");
      const double yaw = euler_zyx_from_quaternion(last_state_.q_WB).z();
      const double d = c.args[0] / 100.0;
      Eigen::Vector3d delta_H = Eigen::Vector3d::Zero();
      double dyaw = 0.0;
      double speed = move_speed_mps_;
      switch (c.verb) {
        case Verb::up: delta_H.z() = d; break;
        case Verb::down: delta_H.z() = -d; break;
        case Verb::left: delta_H.y() = d; break;
        case Verb::right: delta_H.y() = -d; break;
        case Verb::forward: delta_H.x() = d; break;
        case Verb::back: delta_H.x() = -d; break;
        case Verb::cw: dyaw = -c.args[0] / kDegPerRad; break;
        case Verb::ccw: dyaw = c.args[0] / kDegPerRad; break;
        default:  // go x y z speed
          delta_H = Eigen::Vector3d(c.args[0], c.args[1], c.args[2]) / 100.0;
          speed = c.args[3] / 100.0;
      }
      sticks_ = {};
      capture_references(last_state_);
      manoeuvre_ = {true, c.verb, p_ref_ + heading_to_world(yaw, delta_H), yaw_ref_ + dyaw, speed};
      return std::nullopt;
    }
    case Verb::flip: case Verb::curve:
      return refuse("refused: flip and curve are not simulated", "error");
    default:
      return read_reply(c.verb);
  }
}

std::string Autopilot::read_reply(sdk::Verb verb) const {
  using sdk::Verb;
  char buf[96];
  const Eigen::Vector3d rpy = euler_zyx_from_quaternion(last_state_.q_WB) * kDegPerRad;
  switch (verb) {
    case Verb::speed_q: std::snprintf(buf, sizeof buf, "%.1f", move_speed_mps_ * 100.0); break;
    case Verb::battery_q: std::snprintf(buf, sizeof buf, "%d", battery_pct()); break;
    case Verb::time_q: std::snprintf(buf, sizeof buf, "%llds", static_cast<long long>(motor_on_ns_ / kNsPerSecond)); break;
    case Verb::height_q:
      std::snprintf(buf, sizeof buf, "%lddm", std::lround(std::max(0.0, height_above_takeoff_m()) * 10.0));
      break;
    case Verb::tof_q: std::snprintf(buf, sizeof buf, "%ldmm", std::lround(tof_m() * 1000.0)); break;
    case Verb::attitude_q:
      // The Tello's yaw is clockwise-positive (sdk_messages.hpp).
      std::snprintf(buf, sizeof buf, "pitch:%ld;roll:%ld;yaw:%ld;", std::lround(rpy.y()), std::lround(rpy.x()),
                    std::lround(-rpy.z()));
      break;
    case Verb::baro_q: std::snprintf(buf, sizeof buf, "%.6f", last_state_.p_WB_m.z()); break;
    case Verb::temp_q: return "60~62C";  // no thermal model: the nominal board temperature
    case Verb::wifi_q: return "90";      // no radio model: a good link
    case Verb::sdk_q: return "20";
    case Verb::sn_q: return "0TQZSIM0000001";
    case Verb::acceleration_q: {
      const Eigen::Vector3d a_mg = specific_force_B_ / vehicle_.gravity_mps2 * 1000.0;
      // The Tello's body axes are x forward, y right, z down: agz ~ -1000 at rest.
      std::snprintf(buf, sizeof buf, "agx:%.2f;agy:%.2f;agz:%.2f;", a_mg.x(), -a_mg.y(), -a_mg.z());
      break;
    }
    default: return "error";
  }
  return buf;
}

std::vector<SdkReply> Autopilot::take_replies() {
  std::vector<SdkReply> out;
  out.swap(replies_);
  return out;
}

void Autopilot::capture_references(const RigidBodyState& s) {
  p_ref_ = s.p_WB_m;
  v_ref_ = s.v_WB_W_mps;
  a_ff_.setZero();
  yaw_ref_ = euler_zyx_from_quaternion(s.q_WB).z();
  yaw_rate_ref_ = 0.0;
}

void Autopilot::reset_integrators() {
  vel_integral_.setZero();
  rate_integral_.setZero();
}

void Autopilot::rc_references(double dt, double yaw) {
  const double vh = params_.rc_horizontal_mps_at_100 * (params_.fast_mode ? params_.fast_mode_speed_factor : 1.0);
  const Eigen::Vector3d v_H(sticks_[1] / 100.0 * vh, -sticks_[0] / 100.0 * vh,
                            sticks_[2] / 100.0 * params_.rc_vertical_mps_at_100);
  const Eigen::Vector3d v_cmd = heading_to_world(yaw, v_H);
  const double r_cmd = -sticks_[3] / 100.0 * params_.rc_yaw_radps_at_100;
  // First-order reference models, discretised exactly for the tick: x += (u - x)(1 - e^{-dt/tau}).
  const double th = params_.velocity_time_constant_s, tz = params_.vertical_time_constant_s;
  const Eigen::Vector3d tau(th, th, tz);
  for (int i = 0; i < 3; ++i) {
    a_ff_[i] = (v_cmd[i] - v_ref_[i]) / tau[i];
    v_ref_[i] += (v_cmd[i] - v_ref_[i]) * -std::expm1(-dt / tau[i]);
  }
  yaw_rate_ref_ += (r_cmd - yaw_rate_ref_) * -std::expm1(-dt / params_.yaw_time_constant_s);
  p_ref_ += v_ref_ * dt;
  yaw_ref_ += yaw_rate_ref_ * dt;
}

void Autopilot::manoeuvre_references(TimeNs t_ns, double dt, const RigidBodyState& s) {
  Manoeuvre& m = manoeuvre_;
  const Eigen::Vector3d to_go = m.target_W_m - p_ref_;
  const double dist = to_go.norm();
  const double step = m.speed_mps * dt;
  a_ff_.setZero();
  if (dist > step) {
    v_ref_ = to_go / dist * m.speed_mps;
    p_ref_ += v_ref_ * dt;
  } else {
    p_ref_ = m.target_W_m;
    v_ref_.setZero();
  }
  const double yaw_to_go = m.target_yaw_rad - yaw_ref_;
  const double yaw_step = params_.rc_yaw_radps_at_100 * dt;
  if (std::abs(yaw_to_go) > yaw_step) {
    yaw_rate_ref_ = std::copysign(params_.rc_yaw_radps_at_100, yaw_to_go);
    yaw_ref_ += yaw_rate_ref_ * dt;
  } else {
    yaw_ref_ = m.target_yaw_rad;
    yaw_rate_ref_ = 0.0;
  }
  const double yaw = euler_zyx_from_quaternion(s.q_WB).z();
  const bool settled = p_ref_ == m.target_W_m && yaw_ref_ == m.target_yaw_rad &&
                       (s.p_WB_m - m.target_W_m).norm() < 0.10 && s.v_WB_W_mps.norm() < 0.15 &&
                       std::abs(wrap_pi(yaw - m.target_yaw_rad)) < 0.05 && s.w_WB_B_radps.norm() < 0.2;
  if (settled) {
    m.active = false;
    reply(t_ns, "ok");
  }
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
  const bool on_ground = s.p_WB_m.z() <= rest_z() + kOnGroundTolerance_m;
  const bool motors_on = mode_ == FlightMode::taking_off || mode_ == FlightMode::flying || mode_ == FlightMode::landing;
  if (motors_on) motor_on_ns_ += static_cast<TimeNs>(std::llround(dt * 1e9));

  // Watchdog: no command at all for watchdog_s while flying -> land by itself.
  if ((mode_ == FlightMode::taking_off || mode_ == FlightMode::flying) &&
      t_ns - last_command_ns_ >= seconds_to_ns(params_.watchdog_s))
    start_landing(false);

  const double yaw = euler_zyx_from_quaternion(s.q_WB).z();
  switch (mode_) {
    case FlightMode::landed:
      reset_integrators();
      return Eigen::Vector4d::Zero();
    case FlightMode::emergency:
      reset_integrators();
      if (on_ground && s.v_WB_W_mps.norm() < 1e-6) mode_ = FlightMode::landed;
      return Eigen::Vector4d::Zero();
    case FlightMode::taking_off: {
      if (t_ns - phase_start_ns_ < seconds_to_ns(params_.takeoff_spinup_s)) {
        capture_references(s);
        reset_integrators();
        return Eigen::Vector4d::Constant(vehicle_.rotor_speed_min_radps);
      }
      const double z_target = vehicle_.floor_z_m + params_.takeoff_height_m;
      // Climb at takeoff_climb_mps, easing into the target height: the reference speed is
      // min(climb, remaining / 0.3 s), changing at most 1 m/s^2; p_ref integrates it exactly.
      // While still on the floor the reference waits for the vehicle (no lead to catch up on).
      if (on_ground) p_ref_.z() = s.p_WB_m.z();
      const double remaining = z_target - p_ref_.z();
      a_ff_.setZero();
      v_ref_.head<2>().setZero();
      if (remaining > 2e-3) {
        const double vz_target = std::min(params_.takeoff_climb_mps, remaining / 0.3);
        const double dv = std::clamp(vz_target - v_ref_.z(), -1.0 * dt, 1.0 * dt);
        v_ref_.z() += dv;
        a_ff_.z() = dt > 0.0 ? dv / dt : 0.0;
        p_ref_.z() += v_ref_.z() * dt;
      } else {
        p_ref_.z() = z_target;
        v_ref_.z() = 0.0;
      }
      const bool settled = z_target - p_ref_.z() < 0.02 && std::abs(s.p_WB_m.z() - z_target) < 0.03 &&
                           s.v_WB_W_mps.norm() < 0.1;
      if (settled && !settled_since_ns_) settled_since_ns_ = t_ns;
      if (settled_since_ns_ && t_ns - *settled_since_ns_ >= seconds_to_ns(params_.takeoff_reply_delay_s)) {
        mode_ = FlightMode::flying;
        if (reply_takeoff_) reply(t_ns, "ok");
        reply_takeoff_ = false;
      }
      break;
    }
    case FlightMode::flying:
      if (manoeuvre_.active) {
        manoeuvre_references(t_ns, dt, s);
      } else {
        rc_references(dt, yaw);
      }
      break;
    case FlightMode::landing:
      if (on_ground) {
        mode_ = FlightMode::landed;
        if (reply_land_) reply(t_ns, "ok");
        reply_land_ = false;
        reset_integrators();
        return Eigen::Vector4d::Zero();
      }
      // Descend at land_speed_mps; the reference may go below the floor so the vehicle
      // keeps settling onto it.
      v_ref_ = Eigen::Vector3d(0.0, 0.0, -params_.land_speed_mps);
      a_ff_.setZero();
      p_ref_.z() = std::max(p_ref_.z() - params_.land_speed_mps * dt, rest_z() - 0.2);
      yaw_rate_ref_ = 0.0;
      break;
  }
  return control(dt, s, on_ground);
}

Eigen::Vector4d Autopilot::control(double dt, const RigidBodyState& s, bool on_ground) {
  const AutopilotParams& P = params_;
  const double m = vehicle_.mass_kg, g = vehicle_.gravity_mps2;
  const Eigen::Matrix3d R = s.q_WB.toRotationMatrix();

  // Position -> velocity, with the reference leashed to the vehicle.
  Eigen::Vector3d e_p = p_ref_ - s.p_WB_m;
  if (e_p.norm() > P.position_leash_m) {
    e_p *= P.position_leash_m / e_p.norm();
    p_ref_ = s.p_WB_m + e_p;
  }
  const Eigen::Vector3d k_p(P.pos_gain_per_s, P.pos_gain_per_s, P.pos_gain_z_per_s);
  const Eigen::Vector3d k_v(P.vel_gain_per_s, P.vel_gain_per_s, P.vel_gain_z_per_s);
  const Eigen::Vector3d e_v = v_ref_ + k_p.cwiseProduct(e_p) - s.v_WB_W_mps;
  const Eigen::Vector3d a_cmd = a_ff_ + k_v.cwiseProduct(e_v) + vel_integral_;

  // Thrust vector: f = m (a + g e3), its tilt limited to the speed mode's limit.
  Eigen::Vector3d f = m * (a_cmd + Eigen::Vector3d(0.0, 0.0, g));
  f.z() = std::clamp(f.z(), 0.2 * m * g, 1.8 * m * g);
  const double f_h = std::hypot(f.x(), f.y());
  // Aim 2 % inside the limit so that attitude-tracking transients stay within it.
  const double f_h_max = f.z() * std::tan(0.98 * tilt_limit_rad());
  const bool tilt_saturated = f_h > f_h_max;
  if (tilt_saturated) {
    f.x() *= f_h_max / f_h;
    f.y() *= f_h_max / f_h;
  }
  // Integral with conditional integration (anti-windup): frozen on the ground and while the
  // thrust vector or the motors saturate.
  if (!on_ground) {
    const Eigen::Vector3d di = P.vel_integral_gain_per_s2 * e_v * dt;
    if (!tilt_saturated && !was_saturated_) vel_integral_.head<2>() += di.head<2>();
    if (!was_saturated_) vel_integral_.z() += di.z();
    vel_integral_ = vel_integral_.cwiseMax(-2.0).cwiseMin(2.0);
  }

  // Desired attitude: z_B along f, x_B in the plane of the yaw reference.
  const Eigen::Vector3d z_d = f.normalized();
  const Eigen::Vector3d x_c(std::cos(yaw_ref_), std::sin(yaw_ref_), 0.0);
  const Eigen::Vector3d y_d = z_d.cross(x_c).normalized();
  Eigen::Matrix3d R_d;
  R_d.col(0) = y_d.cross(z_d);
  R_d.col(1) = y_d;
  R_d.col(2) = z_d;
  const double thrust = std::max(0.0, f.dot(R.col(2)));

  // Attitude error as a rotation vector of the body relative to the desired attitude.
  Eigen::Quaterniond q_e = Eigen::Quaterniond(R_d).conjugate() * s.q_WB;
  if (q_e.w() < 0.0) q_e.coeffs() = -q_e.coeffs();
  const Eigen::Vector3d e_att = 2.0 * q_e.vec();
  Eigen::Vector3d w_d(-P.att_gain_per_s * e_att.x(), -P.att_gain_per_s * e_att.y(), -P.yaw_gain_per_s * e_att.z());
  w_d += R.transpose() * Eigen::Vector3d(0.0, 0.0, yaw_rate_ref_);
  w_d.head<2>() = w_d.head<2>().cwiseMax(-P.max_tilt_rate_radps).cwiseMin(P.max_tilt_rate_radps);
  w_d.z() = std::clamp(w_d.z(), -P.max_yaw_rate_radps, P.max_yaw_rate_radps);

  // Body rates -> torque (PI, plus the rigid body's and the rotors' gyroscopic terms).
  const Eigen::Vector3d& w = s.w_WB_B_radps;
  const Eigen::Vector3d e_w = w_d - w;
  const Eigen::Vector3d k_w(P.rate_gain_per_s, P.rate_gain_per_s, P.yaw_rate_gain_per_s);
  const Eigen::Vector3d alpha = k_w.cwiseProduct(e_w) + rate_integral_;
  const Eigen::Vector3d I = vehicle_.inertia_kgm2;
  const Eigen::Vector3d h_rotor(0.0, 0.0, vehicle_.rotor_inertia_kgm2 * net_rotor_speed_radps(s.rotor_speed_radps));
  const Eigen::Vector3d torque = I.cwiseProduct(alpha) + w.cross(I.cwiseProduct(w) + h_rotor);

  bool saturated = false;
  const Eigen::Vector4d cmd = mix(thrust, torque, saturated);
  was_saturated_ = saturated;
  if (!saturated && !on_ground) {
    rate_integral_ += P.rate_integral_gain_per_s2 * e_w * dt;
    rate_integral_ = rate_integral_.cwiseMax(-5.0).cwiseMin(5.0);
  }
  return cmd;
}

Eigen::Vector4d Autopilot::mix(double thrust_N, const Eigen::Vector3d& tau, bool& saturated) const {
  // Inverse of the mixer of plant/dynamics.hpp in rotor thrusts f_i = b Omega_i^2:
  //   f_i = T/4 + sy_i tau_x / (4 a_y) - sx_i tau_y / (4 a_x) - spin_i tau_z / (4 d / b)
  const double b = vehicle_.thrust_coeff_N_per_radps2;
  const double k = vehicle_.torque_coeff_Nm_per_radps2 / b;
  const double f_min = b * vehicle_.rotor_speed_min_radps * vehicle_.rotor_speed_min_radps;
  const double f_max = b * vehicle_.rotor_speed_max_radps * vehicle_.rotor_speed_max_radps;
  Eigen::Vector4d f_rp, f_y;
  for (int i = 0; i < 4; ++i) {
    f_rp[i] = kRotorSy[i] * tau.x() / (4.0 * vehicle_.arm_y_m) - kRotorSx[i] * tau.y() / (4.0 * vehicle_.arm_x_m);
    f_y[i] = -kRotorSpin[i] * tau.z() / (4.0 * k);
  }
  double f_t = thrust_N / 4.0;
  saturated = false;
  // 1. Roll and pitch must fit: scale them down if their spread exceeds the range.
  const double spread = f_rp.maxCoeff() - f_rp.minCoeff();
  if (spread > f_max - f_min) {
    f_rp *= (f_max - f_min) / spread;
    saturated = true;
  }
  // 2. Shift the collective so roll and pitch fit.
  const double lo = f_t + f_rp.minCoeff(), hi = f_t + f_rp.maxCoeff();
  if (lo < f_min) { f_t += f_min - lo; saturated = true; }
  if (hi > f_max) { f_t -= hi - f_max; saturated = true; }
  // 3. Yaw gets what is left: the largest scale s in [0, 1] keeping every rotor in range.
  double s = 1.0;
  for (int i = 0; i < 4; ++i) {
    const double base = f_t + f_rp[i];
    if (f_y[i] > 0.0) s = std::min(s, (f_max - base) / f_y[i]);
    if (f_y[i] < 0.0) s = std::min(s, (f_min - base) / f_y[i]);
  }
  s = std::clamp(s, 0.0, 1.0);
  if (s < 1.0) saturated = true;
  Eigen::Vector4d cmd;
  for (int i = 0; i < 4; ++i) {
    const double fi = std::clamp(f_t + f_rp[i] + s * f_y[i], f_min, f_max);
    cmd[i] = std::sqrt(fi / b);
  }
  return cmd;
}

}  // namespace shelfcross::plant

#include "plant/flight_controller.hpp"

#include <algorithm>
#include <cmath>

#include "plant/mixer.hpp"

namespace shelfcross::plant {

FlightController::FlightController(const AutopilotParams& params, const VehicleParams& vehicle)
    : params_(params), vehicle_(vehicle) {}

double FlightController::tilt_limit_rad() const {
  return params_.fast_mode ? params_.tilt_limit_fast_rad : params_.tilt_limit_slow_rad;
}

void FlightController::reset_integrators() {
  vel_integral_.setZero();
  rate_integral_.setZero();
}

Eigen::Vector4d FlightController::control(double dt, const RigidBodyState& s, const SensedState& sensed,
                                          FlightReferences& ref, bool on_ground) {
  const AutopilotParams& P = params_;
  const double m = vehicle_.mass_kg, g = vehicle_.gravity_mps2;
  const Eigen::Matrix3d R = s.q_WB.toRotationMatrix();

  // Position -> velocity on the sensed state, with the reference leashed to the estimate. A
  // lost horizontal hold keeps the reference on the estimate and flies the sticks' attitude.
  const Eigen::Vector3d& p = sensed.p_W_m;
  const bool hold = sensed.horizontal_hold;
  if (!hold) ref.p_W_m.head<2>() = p.head<2>();
  Eigen::Vector3d e_p = ref.p_W_m - p;
  if (e_p.norm() > P.position_leash_m) {
    e_p *= P.position_leash_m / e_p.norm();
    ref.p_W_m = p + e_p;
  }
  const Eigen::Vector3d k_p(P.loops.pos_gain_per_s, P.loops.pos_gain_per_s, P.loops.pos_gain_z_per_s);
  const Eigen::Vector3d k_v(P.loops.vel_gain_per_s, P.loops.vel_gain_per_s, P.loops.vel_gain_z_per_s);
  Eigen::Vector3d e_v = ref.v_W_mps + k_p.cwiseProduct(e_p) - sensed.v_W_mps;
  Eigen::Vector3d a_cmd = ref.a_ff_W_mps2 + k_v.cwiseProduct(e_v) + vel_integral_;
  if (!hold) {
    e_v.head<2>().setZero();
    a_cmd.head<2>() = ref.a_ff_W_mps2.head<2>() + attitude_mode_acceleration(ref.v_W_mps) + vel_integral_.head<2>();
  }

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
    const Eigen::Vector3d di = P.loops.vel_integral_gain_per_s2 * e_v * dt;
    if (!tilt_saturated && !was_saturated_) vel_integral_.head<2>() += di.head<2>();
    if (!was_saturated_) vel_integral_.z() += di.z();
    vel_integral_ = vel_integral_.cwiseMax(-2.0).cwiseMin(2.0);
  }

  // Desired attitude: z_B along f, x_B in the plane of the yaw reference.
  const Eigen::Vector3d z_d = f.normalized();
  const Eigen::Vector3d x_c(std::cos(ref.yaw_rad), std::sin(ref.yaw_rad), 0.0);
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
  Eigen::Vector3d w_d(-P.loops.att_gain_per_s * e_att.x(), -P.loops.att_gain_per_s * e_att.y(), -P.loops.yaw_gain_per_s * e_att.z());
  w_d += R.transpose() * Eigen::Vector3d(0.0, 0.0, ref.yaw_rate_radps);
  w_d.head<2>() = w_d.head<2>().cwiseMax(-P.loops.max_tilt_rate_radps).cwiseMin(P.loops.max_tilt_rate_radps);
  w_d.z() = std::clamp(w_d.z(), -P.loops.max_yaw_rate_radps, P.loops.max_yaw_rate_radps);

  // Body rates -> torque (PI, plus the rigid body's and the rotors' gyroscopic terms).
  const Eigen::Vector3d& w = s.w_WB_B_radps;
  const Eigen::Vector3d e_w = w_d - w;
  const Eigen::Vector3d k_w(P.loops.rate_gain_per_s, P.loops.rate_gain_per_s, P.loops.yaw_rate_gain_per_s);
  const Eigen::Vector3d alpha = k_w.cwiseProduct(e_w) + rate_integral_;
  const Eigen::Vector3d I = vehicle_.inertia_kgm2;
  const Eigen::Vector3d h_rotor(0.0, 0.0, vehicle_.rotor_inertia_kgm2 * net_rotor_speed_radps(s.rotor_speed_radps));
  const Eigen::Vector3d torque = I.cwiseProduct(alpha) + w.cross(I.cwiseProduct(w) + h_rotor);

  bool saturated = false;
  const Eigen::Vector4d cmd = mix_rotor_speeds(vehicle_, thrust, torque, saturated);
  was_saturated_ = saturated;
  if (!saturated && !on_ground) {
    rate_integral_ += P.loops.rate_integral_gain_per_s2 * e_w * dt;
    rate_integral_ = rate_integral_.cwiseMax(-5.0).cwiseMin(5.0);
  }
  return cmd;
}

Eigen::Vector2d FlightController::attitude_mode_acceleration(const Eigen::Vector3d& v_ref_W_mps) const {
  const Eigen::Vector2d v = v_ref_W_mps.head<2>();
  const double k = vehicle_.linear_drag_Ns_per_m.x() + vehicle_.quadratic_drag_Ns2_per_m2.x() * v.norm();
  return k * v / vehicle_.mass_kg;
}

}  // namespace shelfcross::plant

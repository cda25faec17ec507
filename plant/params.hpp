#pragma once
// Parameters of the simulated Tello: airframe, rotors, drag, wind, and the onboard autopilot.
// Plain data with defaults; every default states its source or derivation beside it.
// Scenario files (verification/) set them; campaigns disperse them.
//
// OWNERSHIP NOTE for the plant's author: the field list is the contract the scenario loader
// reads; fill in the derivations and adjust defaults, and keep names carrying units.

#include <Eigen/Core>

namespace shelfcross::plant {

/// Which terms of the right-hand side are on. With all of these off, the right-hand side is
/// paper eq. 9 term by term (rotor speeds applied instantly, no drag, no wind).
struct ModelSwitches {
  bool motor_dynamics = true;   ///< first-order rotor speed response instead of instant
  bool gyroscopic = true;       ///< the Jr * Om rotor gyroscopic term of eq. 9
  bool linear_drag = true;
  bool quadratic_drag = true;
  bool wind = true;
  bool operator==(const ModelSwitches&) const = default;
};

struct VehicleParams {
  double mass_kg = 0.080;               ///< Tello with battery (METHOD.md Table 4)
  double gravity_mps2 = 9.80665;
  Eigen::Vector3d size_m = Eigen::Vector3d(0.098, 0.0925, 0.041);  ///< x, y, z incl. propellers
  Eigen::Vector3d inertia_kgm2 = Eigen::Vector3d(0.0, 0.0, 0.0);  ///< Ixx Iyy Izz (derive)
  double arm_x_m = 0.0;   ///< |x| of each rotor axis from the centre of mass (X layout)
  double arm_y_m = 0.0;   ///< |y| of each rotor axis
  double rotor_inertia_kgm2 = 0.0;      ///< Jr of one rotor + motor bell
  double thrust_coeff_N_per_radps2 = 0.0;   ///< b: thrust = b * Omega^2
  double torque_coeff_Nm_per_radps2 = 0.0;  ///< d: reaction torque = d * Omega^2
  double rotor_speed_max_radps = 0.0;
  double rotor_speed_min_radps = 0.0;   ///< idle while armed and flying
  double motor_time_constant_s = 0.02;
  Eigen::Vector3d linear_drag_Ns_per_m = Eigen::Vector3d::Zero();     ///< body-frame, per axis
  Eigen::Vector3d quadratic_drag_Ns2_per_m2 = Eigen::Vector3d::Zero();  ///< body-frame, per axis
  ModelSwitches switches;
  bool operator==(const VehicleParams&) const = default;
};

/// Wind: a steady world-frame velocity plus gusts from a seeded stream.
struct WindParams {
  Eigen::Vector3d steady_W_mps = Eigen::Vector3d::Zero();
  double gust_stddev_mps = 0.0;       ///< per axis, of a first-order (Ornstein-Uhlenbeck) gust
  double gust_time_constant_s = 1.0;
  bool operator==(const WindParams&) const = default;
};

/// The Tello's onboard autopilot as an SDK user experiences it. rc-to-velocity gains and time
/// constants have no published identification (PROTOCOL.md gives plausible ranges); campaigns
/// disperse them.
struct AutopilotParams {
  double rate_hz = 500.0;               ///< inner-loop rate; the plant's input-hold interval
  double rc_horizontal_mps_at_100 = 1.0;  ///< slow mode speed at full stick
  double rc_vertical_mps_at_100 = 1.0;
  double rc_yaw_radps_at_100 = 1.5;
  double fast_mode_speed_factor = 2.0;  ///< fast mode multiplies horizontal speed
  double velocity_time_constant_s = 0.5;  ///< first-order response of horizontal velocity to rc
  double vertical_time_constant_s = 0.4;
  double yaw_time_constant_s = 0.3;
  double tilt_limit_slow_rad = 0.15707963267948966;  ///< 9 deg (PROTOCOL.md)
  double tilt_limit_fast_rad = 0.43633231299858238;  ///< 25 deg (PROTOCOL.md)
  double takeoff_height_m = 1.0;        ///< PROTOCOL.md: 0.8..1.2 m
  double takeoff_reply_delay_s = 0.5;   ///< hold after reaching height before "ok"
  double land_speed_mps = 0.5;
  double watchdog_s = 15.0;             ///< auto-land without any command
  bool operator==(const AutopilotParams&) const = default;
};

}  // namespace shelfcross::plant

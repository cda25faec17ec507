#pragma once
// Parameters of the simulated Tello: airframe, rotors, drag, wind, and the onboard autopilot.
// Plain data with defaults; every default states its source or derivation beside it.
// Scenario files (verification/) set them; campaigns disperse them.
//
// Rotor numbering, positions and spin (seen from above, x forward, y left, z up):
//
//          front (+x)
//      1 (ccw)   2 (cw)          rotor i at (sx_i * arm_x, sy_i * arm_y, 0) in B
//           \   /                 sx = (+1, +1, -1, -1),  sy = (+1, -1, -1, +1)
//            [B]                  spin s_i = +1 (ccw, angular velocity along +z_B) for 1, 3
//           /   \                            -1 (cw) for 2, 4
//      4 (cw)    3 (ccw)          (the Tello's own props: front-left and rear-right ccw)
//          rear
//
// See plant/dynamics.hpp for the mixer derived from this layout.
//
// OWNERSHIP NOTE: the field list is the contract the scenario loader reads; fields may be
// added, never renamed or removed.

#include <cmath>

#include <Eigen/Core>

#include "sdk/command.hpp"
#include "shelfcross/gravity.hpp"

namespace shelfcross::plant {

/// Which terms of the right-hand side are on. With all of these off, the right-hand side is
/// paper eq. 9 term by term (rotor speeds applied instantly, no drag, no wind).
struct ModelSwitches {
  bool motor_dynamics = true;   ///< first-order rotor speed response instead of instant
  bool gyroscopic = true;       ///< the Jr * Om rotor gyroscopic term of eq. 9 (and the
                                ///< reaction of rotor spin-up, -Jr * dOm/dt, about z_B)
  bool linear_drag = true;
  bool quadratic_drag = true;
  bool wind = true;             ///< wind enters through the drag (air-relative velocity)
  bool operator==(const ModelSwitches&) const = default;
};

/// How the defaults below were derived (all SI). Kept as named constants so the arithmetic is
/// visible and checked by the compiler rather than copied as opaque numbers.
namespace tello_derivation {
inline constexpr double kMass_kg = 0.080;          // docs/method.md Table 4 (Tello with battery)
inline constexpr double kSizeX_m = 0.098, kSizeY_m = 0.0925, kSizeZ_m = 0.041;  // Table 4
// Propellers inside the 98 x 92.5 mm outline: tips reach the outline and the two props of a
// side clear each other by 2 mm, so r_p + a_y = 92.5/2 and a_y = r_p + 1 mm:
inline constexpr double kPropRadius_m = (kSizeY_m / 2.0 - 0.001) / 2.0;       // 22.6 mm
inline constexpr double kArmY_m = kPropRadius_m + 0.001;                      // 23.6 mm
inline constexpr double kArmX_m = kSizeX_m / 2.0 - kPropRadius_m;             // 26.4 mm
// Inertia: a 60 g central box (battery, board, camera, shell) of 60 x 45 x 41 mm plus four
// 5 g point masses (8520 coreless motor ~3 g, prop, guard) at the rotor hubs.
inline constexpr double kBodyMass_kg = 0.060, kRotorMass_kg = 0.005;
inline constexpr double kBodyX_m = 0.060, kBodyY_m = 0.045, kBodyZ_m = kSizeZ_m;
inline constexpr double kIxx = kBodyMass_kg * (kBodyY_m * kBodyY_m + kBodyZ_m * kBodyZ_m) / 12.0 +
                               4.0 * kRotorMass_kg * kArmY_m * kArmY_m;   // 3.0e-5 kg m^2
inline constexpr double kIyy = kBodyMass_kg * (kBodyX_m * kBodyX_m + kBodyZ_m * kBodyZ_m) / 12.0 +
                               4.0 * kRotorMass_kg * kArmX_m * kArmX_m;   // 4.0e-5 kg m^2
inline constexpr double kIzz = kBodyMass_kg * (kBodyX_m * kBodyX_m + kBodyY_m * kBodyY_m) / 12.0 +
                               4.0 * kRotorMass_kg * (kArmX_m * kArmX_m + kArmY_m * kArmY_m);  // 5.3e-5
// Thrust T = C_T rho n^2 D^4 (n in rev/s) with C_T = 0.10 (typical of small two-blade props at
// low Reynolds number), rho = 1.225 kg/m^3, D = 2 r_p; per rad/s: b = C_T rho D^4 / (2 pi)^2.
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kAirDensity_kgpm3 = 1.225;
inline constexpr double kPropDiameter_m = 2.0 * kPropRadius_m;
inline constexpr double kCT = 0.10, kCP = 0.05;
inline constexpr double kD4 = kPropDiameter_m * kPropDiameter_m * kPropDiameter_m * kPropDiameter_m;
inline constexpr double kThrustCoeff = kCT * kAirDensity_kgpm3 * kD4 / (4.0 * kPi * kPi);  // 1.30e-8
// Reaction torque Q = C_P / (2 pi) rho n^2 D^5 with C_P = 0.05: d = b * C_P D / (2 pi C_T).
inline constexpr double kTorqueCoeff = kThrustCoeff * kCP * kPropDiameter_m / (2.0 * kPi * kCT);  // 4.7e-11
// Hover: 4 b Om^2 = m g  ->  Om_hover = sqrt(m g / 4 b) = 3883 rad/s (37,100 rpm, a plausible
// loaded speed for 8520 coreless motors on 45 mm props).
// Maximum: thrust-to-weight 2 -> Om_max = sqrt(2) Om_hover = 5491 rad/s; idle 1200 rad/s
// (10 % of hover thrust per rotor).
// Drag, fitted so that steady level flight at the Tello's speed-mode limits matches
// docs/tello_sdk.md / Table 4: 9 deg tilt -> 4 m/s (slow) and 25 deg tilt -> 8 m/s (fast, the
// top speed). Body-frame drag F = -k_lin v - k_quad |v| v per axis, k_lin isotropic (rotor
// induced drag), k_quad,z = k_quad,x * (98 x 92.5) / (92.5 x 41) (top vs frontal area). The
// 2 x 2 system (force balance at both points) solved numerically gives the numbers below;
// PlantPhysics.TopSpeedAt25DegTiltIs8mps re-checks them by simulation.
inline constexpr double kLinearDrag = 0.01351;   // N s/m
inline constexpr double kQuadDragXY = 0.004444;  // N s^2/m^2 (~ 0.5 rho Cd A with Cd A = 7.3 cm^2)
inline constexpr double kQuadDragZ = kQuadDragXY * (kSizeX_m * kSizeY_m) / (kSizeY_m * kSizeZ_m);
}  // namespace tello_derivation

/// The air near a solid surface, per rotor (plant/surface_effects.hpp): ground effect below a
/// rotor and ceiling effect above it, from the distance to the nearest surface along the rotor's
/// axis. Each coefficient scales its model's excess thrust; 0 switches the effect off (the
/// default: the open-air rotor of the rest of this file), 1 is the published model.
struct SurfaceEffectParams {
  double rotor_radius_m = tello_derivation::kPropRadius_m;  ///< R, 22.6 mm (tello_derivation)
  double ground_coeff = 0.0;   ///< k_g: 1 is Cheeseman & Bennett's T_IGE / T_OGE = 1 / (1 - (R / 4z)^2)
  double ceiling_coeff = 0.0;  ///< k_c: 1 is the ceiling model of surface_effects.hpp
  double ceiling_range_radii = 1.0;  ///< the ceiling effect acts within this many radii of the rotor
  bool operator==(const SurfaceEffectParams&) const = default;
  bool any() const { return ground_coeff > 0.0 || ceiling_coeff > 0.0; }
};

struct VehicleParams {
  double mass_kg = tello_derivation::kMass_kg;                 ///< docs/method.md Table 4
  double gravity_mps2 = kStandardGravity_mps2;
  Eigen::Vector3d size_m = Eigen::Vector3d(0.098, 0.0925, 0.041);  ///< x, y, z incl. propellers
  /// Ixx Iyy Izz: central box + four rotor point masses (tello_derivation)
  Eigen::Vector3d inertia_kgm2 = Eigen::Vector3d(tello_derivation::kIxx, tello_derivation::kIyy,
                                                 tello_derivation::kIzz);
  double arm_x_m = tello_derivation::kArmX_m;  ///< |x| of each rotor axis from the centre of mass (X layout)
  double arm_y_m = tello_derivation::kArmY_m;  ///< |y| of each rotor axis
  /// Jr of one rotor + motor rotor: prop 0.25 g as two thin rods of 22.6 mm (m r^2 / 3 =
  /// 4.3e-8) + coreless rotor ~1 g as a 4 mm thin-walled cylinder (m r^2 = 1.6e-8).
  double rotor_inertia_kgm2 = 6.0e-8;
  double thrust_coeff_N_per_radps2 = tello_derivation::kThrustCoeff;   ///< b: thrust = b * Omega^2
  double torque_coeff_Nm_per_radps2 = tello_derivation::kTorqueCoeff;  ///< d: reaction torque = d * Omega^2
  double rotor_speed_max_radps = 5491.0;  ///< thrust-to-weight 2 (tello_derivation)
  double rotor_speed_min_radps = 1200.0;  ///< idle while armed and flying (10 % hover thrust)
  double motor_time_constant_s = 0.02;    ///< small coreless motors: 15..30 ms
  Eigen::Vector3d linear_drag_Ns_per_m = Eigen::Vector3d::Constant(tello_derivation::kLinearDrag);  ///< body-frame, per axis
  Eigen::Vector3d quadratic_drag_Ns2_per_m2 = Eigen::Vector3d(
      tello_derivation::kQuadDragXY, tello_derivation::kQuadDragXY, tello_derivation::kQuadDragZ);  ///< body-frame, per axis
  ModelSwitches switches;
  SurfaceEffectParams surface_effects;
  /// Height of the floor (world z of the surface the vehicle starts on and lands on).
  double floor_z_m = 0.0;
  bool operator==(const VehicleParams&) const = default;

  /// Centre-of-mass height above the floor when resting on it (half the airframe height).
  double rest_height_m() const { return 0.5 * size_m.z(); }
  /// Rotor speed at which the four rotors together carry the weight.
  double hover_rotor_speed_radps() const {
    return std::sqrt(mass_kg * gravity_mps2 / (4.0 * thrust_coeff_N_per_radps2));
  }
};

/// Wind: a steady world-frame velocity plus gusts from a seeded stream.
struct WindParams {
  Eigen::Vector3d steady_W_mps = Eigen::Vector3d::Zero();  ///< indoors: calm by default
  double gust_stddev_mps = 0.0;       ///< per axis, of a first-order (Ornstein-Uhlenbeck) gust
  double gust_time_constant_s = 1.0;
  double gust_sample_period_s = 0.01;  ///< the gust process is drawn on this fixed time grid
  bool operator==(const WindParams&) const = default;
};

/// The autopilot's inner loops (plant/flight_controller.hpp): gains per second, position ->
/// velocity -> acceleration -> attitude -> rate, and the rate limits.
struct LoopGains {
  double pos_gain_per_s = 1.2;
  double pos_gain_z_per_s = 1.5;
  double vel_gain_per_s = 3.0;
  double vel_gain_z_per_s = 4.0;
  double vel_integral_gain_per_s2 = 0.3;
  double att_gain_per_s = 10.0;         ///< roll/pitch angle error -> rate
  double yaw_gain_per_s = 4.0;
  double rate_gain_per_s = 40.0;        ///< roll/pitch rate error -> angular acceleration
  double yaw_rate_gain_per_s = 12.0;
  double rate_integral_gain_per_s2 = 20.0;
  double max_tilt_rate_radps = 4.0;
  double max_yaw_rate_radps = 3.0;
  bool operator==(const LoopGains&) const = default;
};

/// The Tello's onboard autopilot as an SDK user experiences it. rc-to-velocity gains and time
/// constants have no published identification (docs/tello_sdk.md gives plausible ranges); campaigns
/// disperse them.
struct AutopilotParams {
  double rate_hz = 500.0;               ///< inner-loop rate; the plant's input-hold interval (integer Hz)
  double rc_horizontal_mps_at_100 = 1.0;  ///< slow mode speed at full stick (PROTOCOL: 1..4 m/s)
  double rc_vertical_mps_at_100 = 1.0;
  double rc_yaw_radps_at_100 = 1.5;     ///< docs/tello_sdk.md: about 1.5 rad/s at full yaw stick
  double fast_mode_speed_factor = 2.0;  ///< fast mode multiplies horizontal speed
  double velocity_time_constant_s = 0.5;  ///< first-order response of horizontal velocity to rc (0.3..0.7 s)
  double vertical_time_constant_s = 0.4;
  double yaw_time_constant_s = 0.3;
  double tilt_limit_slow_rad = 0.15707963267948966;  ///< 9 deg (docs/tello_sdk.md)
  double tilt_limit_fast_rad = 0.43633231299858238;  ///< 25 deg (docs/tello_sdk.md)
  double takeoff_height_m = 1.0;        ///< docs/tello_sdk.md: 0.8..1.2 m
  double takeoff_reply_delay_s = 0.5;   ///< hold after reaching height before "ok"
  double land_speed_mps = 0.5;          ///< 1 m in ~2 s: docs/tello_sdk.md's "land about 2 s"
  double watchdog_s = sdk::kCommandWatchdog_s;  ///< auto-land without any command
  // --- added by the plant's author ---
  /// Speed mode: false = slow (the Tello's default; 9 deg), true = fast (25 deg, horizontal
  /// rc speed times fast_mode_speed_factor). The SDK has no command for it (the Tello app
  /// switches it), so it is a parameter of the vehicle.
  bool fast_mode = false;
  double takeoff_spinup_s = 1.0;        ///< motors idle on the ground before the climb
  double takeoff_climb_mps = 0.45;      ///< spin-up 1 s + climb ~2.2 s + settle + 0.5 s ~ 4 s
  double move_speed_default_mps = 1.0;  ///< `speed?` default 100 cm/s; `speed x` changes it
  double position_leash_m = 0.5;        ///< the position reference never runs further ahead
  LoopGains loops;                      ///< the inner loops' gains and rate limits
  double battery_endurance_s = 780.0;   ///< 13 min of motor-on time from 100 % (Table 4)
  double battery_start_pct = 100.0;     ///< charge at power-on; drains linearly with motor-on time
  bool operator==(const AutopilotParams&) const = default;
};

}  // namespace shelfcross::plant

#pragma once
// Rigid-body 6-DOF dynamics of the Tello-class quadrotor: paper eq. 9 (docs/method.md section 5)
// stated without Euler angles, plus first-order motors, drag and wind (plant::ModelSwitches).
//
// Frames: W world (x forward, y left, z up, origin on the floor); B body (x forward, y left,
// z up) at the centre of mass. Attitude is the unit quaternion q_WB (R_WB maps B vectors to W);
// roll, pitch, yaw are the ZYX decomposition R_WB = Rz(yaw) Ry(pitch) Rx(roll), only for I/O.
//
// State x = (p_WB_m, v_WB_W_mps, q_WB, w_WB_B_radps, Omega_1..4):
//   p'      = v
//   v'      = -g e3 + R_WB e3 T / m + R_WB F_drag_B / m
//   q'      = 1/2 q (x) (0, w)
//   I w'    = -w x (I w) + tau_mix - w x (Jr Om e3) - Jr Om' e3
//   Omega_i'= (Omega_cmd,i - Omega_i) / tau_m              (motor_dynamics on; else Omega = cmd)
// with T = b sum Omega_i^2 and, for the X layout of params.hpp (rotor i at (sx_i a_x, sy_i a_y)):
//   tau_x = b a_y (O1^2 - O2^2 - O3^2 + O4^2)      (left rotors 1, 4 lift: roll right-down > 0)
//   tau_y = b a_x (-O1^2 - O2^2 + O3^2 + O4^2)     (rear rotors 3, 4 lift: nose down, pitch > 0)
//   tau_z = d (-O1^2 + O2^2 - O3^2 + O4^2)         (ccw rotors 1, 3 react clockwise)
//   Om    = O1 - O2 + O3 - O4                      (net rotor speed along +z_B)
//   F_drag_B = -k_lin . v_air_B - k_quad . |v_air_B| . v_air_B,  v_air_B = R_WB^T (v - wind_W)
//
// Relation to eq. 9 (Euler angles, plus layout): the translational rows are R_WB e3 U1/m - g e3
// written out for ZYX angles; the rotational rows are Euler's equations with U2 = tau_x / l,
// U3 = tau_y / l, U4 = tau_z. eq. 9 prints Om = O2 + O4 - O1 - O3 together with
// U4 = d (O2^2 + O4^2 - O1^2 - O3^2); those two are inconsistent (U4 > 0 for rotors 2, 4 means
// they spin clockwise, i.e. against +z, so their angular momentum is -Jr O e3). The
// gyroscopic torque on the body is -w x h_rotors; we keep eq. 9's form -(Jr/Ix) q Om, +(Jr/Iy) p Om
// with Om the net rotor speed along +z_B, and plant_eq9_test checks that, and the conservation
// of total angular momentum that decides the sign, independently.

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "plant/params.hpp"

namespace shelfcross::plant {

/// Position, velocity, attitude, body rates and rotor speeds of the vehicle.
struct RigidBodyState {
  Eigen::Vector3d p_WB_m = Eigen::Vector3d::Zero();        ///< centre of mass in W
  Eigen::Vector3d v_WB_W_mps = Eigen::Vector3d::Zero();    ///< its velocity in W
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  ///< attitude, unit
  Eigen::Vector3d w_WB_B_radps = Eigen::Vector3d::Zero();  ///< body rates p, q, r
  Eigen::Vector4d rotor_speed_radps = Eigen::Vector4d::Zero();  ///< Omega_1..4, >= 0
};

/// Number of CVODE state components: 3 + 3 + 4 + 3 + 4.
inline constexpr int kStateSize = 17;
/// Layout of the flat state vector: p (0..2), v (3..5), q (w x y z, 6..9), w (10..12), Omega (13..16).
inline constexpr int kIdxP = 0, kIdxV = 3, kIdxQ = 6, kIdxW = 10, kIdxRotor = 13;

/// Spin direction of each rotor: +1 turns counter-clockwise seen from above (angular velocity
/// along +z_B), -1 clockwise.
inline constexpr std::array<double, 4> kRotorSpin = {+1.0, -1.0, +1.0, -1.0};
/// Rotor positions: x = kRotorSx[i] * arm_x_m, y = kRotorSy[i] * arm_y_m.
inline constexpr std::array<double, 4> kRotorSx = {+1.0, +1.0, -1.0, -1.0};
inline constexpr std::array<double, 4> kRotorSy = {+1.0, -1.0, -1.0, +1.0};

/// The mixer: (T, tau_x, tau_y, tau_z) = M * (Omega_1^2 .. Omega_4^2), as derived above.
Eigen::Matrix4d mixer_matrix(const VehicleParams& vehicle);

/// Collective thrust along +z_B (N) and torques about B (N m) from rotor speeds.
struct RotorWrench {
  double thrust_N = 0.0;
  Eigen::Vector3d torque_B_Nm = Eigen::Vector3d::Zero();
};
RotorWrench rotor_wrench(const VehicleParams& vehicle, const Eigen::Vector4d& rotor_speed_radps);

/// Net rotor speed along +z_B, Om = sum_i spin_i Omega_i (rad/s).
double net_rotor_speed_radps(const Eigen::Vector4d& rotor_speed_radps);

/// Time derivative of the flat state y (kStateSize) given the held rotor command (already
/// clamped to the motor's range) and the wind velocity in W. Allocation-free; uses the
/// normalised quaternion for R_WB. Terms follow vehicle.switches. Requires `y` and `ydot` to
/// point at kStateSize doubles each and a non-zero quaternion in y; does not throw.
/// `thrust_factor` multiplies each rotor's thrust b Omega_i^2 (in the collective thrust and in
/// the roll and pitch torques of the mixer): the surface effects of plant/surface_effects.hpp,
/// held over the step; all 1 (exactly the open-air rotor) by default.
void rigid_body_rhs(const VehicleParams& vehicle, const double* y, const Eigen::Vector4d& rotor_cmd_radps,
                    const Eigen::Vector3d& wind_W_mps, double* ydot,
                    const Eigen::Vector4d& thrust_factor = Eigen::Vector4d::Ones());

/// The same on structured types; `ydot` in the flat layout.
std::array<double, kStateSize> rigid_body_rhs(const VehicleParams& vehicle, const RigidBodyState& x,
                                              const Eigen::Vector4d& rotor_cmd_radps,
                                              const Eigen::Vector3d& wind_W_mps,
                                              const Eigen::Vector4d& thrust_factor = Eigen::Vector4d::Ones());

void pack_state(const RigidBodyState& x, double* y);
RigidBodyState unpack_state(const double* y);

/// ZYX Euler angles (roll, pitch, yaw) of R_WB = Rz(yaw) Ry(pitch) Rx(roll); pitch in
/// [-pi/2, pi/2], roll and yaw in (-pi, pi]: shelfcross::euler_zyx (shelfcross/rotation.hpp)
/// of the normalised quaternion's matrix. Requires a non-zero quaternion (a zero one gives NaN).
Eigen::Vector3d euler_zyx_from_quaternion(const Eigen::Quaterniond& q_WB);
/// The unit quaternion of Rz(yaw) Ry(pitch) Rx(roll); any finite angles.
Eigen::Quaterniond quaternion_from_euler_zyx(double roll_rad, double pitch_rad, double yaw_rad);

/// Tilt: the angle between z_B and z_W (rad), in [0, pi]. Requires a non-zero quaternion.
double tilt_rad(const Eigen::Quaterniond& q_WB);

}  // namespace shelfcross::plant

#pragma once
// The Tello's mixer, inverted: the rotor speeds that give a collective thrust and a body torque,
// with saturation handled as the firmware does (yaw authority given up first, then the
// collective shifted, then clipped).

#include <Eigen/Core>

#include "plant/params.hpp"

namespace shelfcross::plant {

/// Inverse of the mixer of plant/dynamics.hpp in rotor thrusts f_i = b Omega_i^2:
///   f_i = T/4 + sy_i tau_x / (4 a_y) - sx_i tau_y / (4 a_x) - spin_i tau_z / (4 d / b),
/// each f_i kept in [b Omega_min^2, b Omega_max^2]: roll and pitch scaled to fit the range, the
/// collective shifted so that they fit, yaw scaled to what is left. Returns the rotor speeds
/// (rad/s); `saturated` tells whether any of the three steps acted.
Eigen::Vector4d mix_rotor_speeds(const VehicleParams& vehicle, double thrust_N, const Eigen::Vector3d& torque_B_Nm,
                                 bool& saturated);

}  // namespace shelfcross::plant

#pragma once
// Angles and rotations, each stated once: degrees and radians, the angle wrap and the ZYX Euler
// decomposition of the attitude convention in sdk_messages.hpp (R = Rz(yaw) Ry(pitch) Rx(roll)).

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Core>

namespace shelfcross {

/// Degrees to radians (the SDK's attitude and turns are whole degrees): a_deg (pi / 180).
constexpr double deg_to_rad(double a_deg) { return a_deg * (std::numbers::pi / 180.0); }
/// Radians to degrees: a_rad (180 / pi).
constexpr double rad_to_deg(double a_rad) { return a_rad * (180.0 / std::numbers::pi); }

/// `a_rad` wrapped into [-pi, pi]: the IEEE remainder by 2 pi, exact (no loop, no drift) for
/// any finite angle. NaN or an infinity gives NaN.
inline double wrap_pi(double a_rad) { return std::remainder(a_rad, 2.0 * std::numbers::pi); }

/// (roll, pitch, yaw) in radians of a rotation R = Rz(yaw) Ry(pitch) Rx(roll):
///   roll = atan2(R21, R22), pitch = asin(-R20) in [-pi/2, pi/2], yaw = atan2(R10, R00).
/// Requires R orthonormal (a rotation matrix); -R20 is clamped to [-1, 1] so that rounding
/// never gives NaN. At pitch = +-pi/2 (gimbal lock) roll and yaw are one angle and the split
/// is atan2's of what rounding leaves.
inline Eigen::Vector3d euler_zyx(const Eigen::Matrix3d& R) {
  return {std::atan2(R(2, 1), R(2, 2)), std::asin(std::clamp(-R(2, 0), -1.0, 1.0)), std::atan2(R(1, 0), R(0, 0))};
}

}  // namespace shelfcross

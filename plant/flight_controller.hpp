#pragma once
// The Tello's inner loops, one tick at a time, on what the firmware senses (plant/tello_senses.hpp):
// position -> velocity (P + feed-forward) -> acceleration (PI, anti-windup) -> thrust vector with
// the speed mode's tilt limit -> attitude (quaternion error, P) -> body rates (PI + gyroscopic
// compensation, anti-windup) -> the mixer's inverse with saturation (plant/mixer.hpp).
//
// Position and velocity are the senses' estimate; attitude and body rates the IMU's (exact).
// Where the VPS is invalid (SensedState::horizontal_hold false) the horizontal hold gives way:
// the reference's horizontal position is kept on the estimate (so the hold resumes where the
// drone is), there is no horizontal position or velocity feedback, and the sticks' reference
// velocity v sets the tilt that would fly it in still air, the drag balance (k_lin + k_quad |v|)
// v / m; so with the sticks at rest the drone flies level and drifts with the air.

#include <Eigen/Core>

#include "plant/dynamics.hpp"
#include "plant/params.hpp"
#include "plant/tello_senses.hpp"

namespace shelfcross::plant {

/// What the inner loops track, in W.
struct FlightReferences {
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_ff_W_mps2 = Eigen::Vector3d::Zero();  ///< acceleration feed-forward
  double yaw_rad = 0.0;
  double yaw_rate_radps = 0.0;
};

class FlightController {
 public:
  FlightController(const AutopilotParams& params, const VehicleParams& vehicle);

  /// One tick of dt seconds: the rotor speed commands (rad/s) that track `ref`. The position
  /// reference is leashed to the estimate (AutopilotParams::position_leash_m), so `ref` may move.
  /// The integrators are frozen on the ground and while the thrust or the motors saturate.
  Eigen::Vector4d control(double dt, const RigidBodyState& s, const SensedState& sensed, FlightReferences& ref,
                          bool on_ground);
  void reset_integrators();
  /// Tilt limit of the current speed mode (rad).
  double tilt_limit_rad() const;

 private:
  /// The thrust acceleration of a lost horizontal hold: the still-air drag balance of v_ref.
  Eigen::Vector2d attitude_mode_acceleration(const Eigen::Vector3d& v_ref_W_mps) const;

  AutopilotParams params_;
  VehicleParams vehicle_;
  Eigen::Vector3d vel_integral_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rate_integral_ = Eigen::Vector3d::Zero();
  bool was_saturated_ = false;
};

}  // namespace shelfcross::plant

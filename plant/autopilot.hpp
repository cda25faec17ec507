#pragma once
// The Tello's onboard autopilot (its firmware) as an SDK user experiences it.
//
// It takes SDK command text (as the drone does, parsed by sdk/command.hpp) and answers
// with the real reply strings; it runs its inner loops at AutopilotParams::rate_hz on the
// vehicle's state (the Tello's own vision/IMU estimate is taken as exact here; sensor models
// belong to verification/).
//
// Behaviour (docs/tello_sdk.md):
//  - Nothing is answered before `command` (SDK mode); `command` -> "ok".
//  - `takeoff` (landed only): motors idle for takeoff_spinup_s, climb at takeoff_climb_mps to
//    takeoff_height_m above the floor, hold, "ok" takeoff_reply_delay_s after settling (~4 s).
//  - `land`: descend at land_speed_mps, motors off at touchdown, then "ok".
//  - `emergency`: motors off at once ("ok"); the vehicle falls; landed once at rest.
//  - `rc a b c d` (never answered; ignored unless flying and no manoeuvre runs): velocity
//    commands in the heading frame H (x forward along the current yaw, y left, z up):
//       v_H = (b, -a) / 100 * V_h,  v_z = c / 100 * V_v,  yaw rate = -d / 100 * W
//    (a + right, d + clockwise seen from above; ours: y left, yaw + counter-clockwise), with
//    V_h = rc_horizontal_mps_at_100 (times fast_mode_speed_factor in fast mode). Each passes a
//    first-order reference model (velocity_, vertical_, yaw_time_constant_s): that is the
//    response an SDK user sees. The references integrate into a position/yaw reference, so zero
//    sticks hold position (the Tello's downward vision does this); the reference is leashed to
//    position_leash_m of the vehicle so saturation never winds it up.
//  - Speed mode: AutopilotParams::fast_mode (tilt limit 25 deg instead of 9 deg).
//  - `speed x` (10..100 cm/s): speed of the moves; `stop`: hover where it is, "ok".
//  - Moves `forward|back|left|right|up|down x`, `cw|ccw x`, `go x y z speed` (heading frame of
//    the moment the move starts, x forward, y left, z up) fly a constant-speed reference and
//    answer "ok" when settled. `flip` and `curve` are parsed but answered "error" (not simulated).
//  - A manoeuvre command while another runs, or one that needs flight while landed: "error".
//  - Watchdog: taking off or flying without any command for watchdog_s -> lands (no reply).
//  - Every command ignored (no effect, no reply) or refused ("error", "out of range", ...)
//    leaves the reason in last_refusal(), for people (`shelfcross plant` prints it).
//  - Reads: battery? "87", height? "3dm", tof? "801mm", time? "12s", speed? "100.0",
//    attitude? "pitch:0;roll:0;yaw:0;", baro? "1.234567", temp? "60~62C", wifi? "90",
//    sdk? "20", sn? (14 characters), acceleration? "agx:..;agy:..;agz:..;".
// Inner loops (each tick): position -> velocity (P + feed-forward) -> acceleration (PI,
// anti-windup) -> thrust vector with the mode's tilt limit -> attitude (quaternion error, P)
// -> body rates (PI + gyroscopic compensation, anti-windup) -> mixer inverse with saturation
// (yaw authority given up first, then collective shifted, then clipped) -> rotor speeds in
// [rotor_speed_min_radps, rotor_speed_max_radps] while armed, 0 when the motors are off.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "plant/dynamics.hpp"
#include "plant/params.hpp"
#include "sdk/command.hpp"
#include "shelfcross/sdk_messages.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

enum class FlightMode { landed, taking_off, flying, landing, emergency };
std::string_view to_string(FlightMode mode);

class Autopilot {
 public:
  /// Throws std::invalid_argument for a non-integer or non-positive rate or bad gains.
  Autopilot(const AutopilotParams& params, const VehicleParams& vehicle);

  /// One command datagram received at t_ns. Returns the immediate reply, if any; manoeuvres
  /// answer later through take_replies().
  std::optional<std::string> on_command(TimeNs t_ns, std::string_view text);
  /// One inner-loop tick at t_ns with the vehicle's state: returns the rotor speed commands
  /// (rad/s), to be held until the next tick.
  Eigen::Vector4d update(TimeNs t_ns, const RigidBodyState& state);
  /// Deferred replies that became due (stamped with the tick that produced them), oldest first.
  std::vector<SdkReply> take_replies();
  /// Why the command of the last on_command call was ignored (no reply, no effect) or refused
  /// (answered with an error), for people; empty when it was carried out.
  const std::string& last_refusal() const { return last_refusal_; }

  FlightMode mode() const { return mode_; }
  bool sdk_mode() const { return sdk_mode_; }
  bool stream_on() const { return stream_on_; }
  bool manoeuvre_active() const { return manoeuvre_.active; }
  /// Tilt limit of the current speed mode (rad).
  double tilt_limit_rad() const;
  int battery_pct() const;
  double motor_on_time_s() const { return ns_to_seconds(motor_on_ns_); }
  /// Height above the take-off point (m), the SDK's `h`.
  double height_above_takeoff_m() const;
  /// Time-of-flight range to the floor (m) as the Tello's sensor reads it (0.1 m on the ground).
  double tof_m() const;
  const AutopilotParams& params() const { return params_; }
  /// Position and yaw references of the inner loops (for logs and tests).
  const Eigen::Vector3d& position_reference_W_m() const { return p_ref_; }
  const Eigen::Vector3d& velocity_reference_W_mps() const { return v_ref_; }

 private:
  struct Manoeuvre {
    bool active = false;
    sdk::Verb verb = sdk::Verb::forward;
    Eigen::Vector3d target_W_m = Eigen::Vector3d::Zero();
    double target_yaw_rad = 0.0;
    double speed_mps = 1.0;
  };

  std::optional<std::string> execute(TimeNs t_ns, const sdk::Command& c);
  // Records why the command had no effect (last_refusal) and returns its reply.
  std::optional<std::string> refuse(std::string why, std::optional<std::string> reply);
  std::string mode_text() const;
  std::string read_reply(sdk::Verb verb) const;
  void start_landing(bool reply_when_done);
  void capture_references(const RigidBodyState& s);
  void reset_integrators();
  void rc_references(double dt, double yaw);
  void manoeuvre_references(TimeNs t_ns, double dt, const RigidBodyState& s);
  Eigen::Vector4d control(double dt, const RigidBodyState& s, bool on_ground);
  Eigen::Vector4d mix(double thrust_N, const Eigen::Vector3d& torque_B_Nm, bool& saturated) const;
  void reply(TimeNs t_ns, std::string text) { replies_.push_back({t_ns, std::move(text)}); }
  double rest_z() const { return vehicle_.floor_z_m + vehicle_.rest_height_m(); }

  AutopilotParams params_;
  VehicleParams vehicle_;
  TimeNs tick_ns_;

  FlightMode mode_ = FlightMode::landed;
  bool sdk_mode_ = false;
  bool stream_on_ = false;
  double move_speed_mps_;
  std::array<int, 4> sticks_{};  // a b c d
  TimeNs last_command_ns_ = 0;
  TimeNs phase_start_ns_ = 0;
  std::optional<TimeNs> settled_since_ns_;
  bool reply_takeoff_ = false, reply_land_ = false;
  Manoeuvre manoeuvre_;

  // References and loop states.
  Eigen::Vector3d p_ref_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_ref_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_ff_ = Eigen::Vector3d::Zero();
  double yaw_ref_ = 0.0, yaw_rate_ref_ = 0.0;
  Eigen::Vector3d vel_integral_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rate_integral_ = Eigen::Vector3d::Zero();
  bool was_saturated_ = false;

  std::optional<TimeNs> last_update_ns_;
  RigidBodyState last_state_;
  Eigen::Vector3d specific_force_B_ = Eigen::Vector3d(0.0, 0.0, 9.80665);
  double takeoff_z_m_;
  TimeNs motor_on_ns_ = 0;
  std::vector<SdkReply> replies_;
  std::string last_refusal_;
};

}  // namespace shelfcross::plant

#pragma once
// The Tello's onboard autopilot (its firmware) as an SDK user experiences it.
//
// It takes SDK command text (as the drone does, parsed by sdk/command.hpp) and answers
// with the real reply strings; it runs its inner loops at AutopilotParams::rate_hz on what its
// senses tell it (plant/tello_senses.hpp): position and velocity from the vision positioning
// system's estimate and the height hold's estimate, attitude and body rates from the IMU
// (exact). Where the VPS is invalid the horizontal hold gives way: the sticks' reference
// velocity sets the tilt that would fly it in still air (the drag balance
// (k_lin + k_quad |v|) v / m), with no position or velocity feedback, so the drone drifts with
// the air; the position reference stays on the estimate, where the hold resumes.
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
//    sdk? "20", sn? (14 characters), acceleration? "agx:..;agy:..;agz:..;". height?, tof? and
//    baro? read the senses (tof? out of range: the state record's invalid 6553 cm, in mm).
// The firmware's parts: its senses (plant/tello_senses.hpp), the SDK interpreter
// (plant/sdk_interpreter.hpp), the flight modes and their references (plant/flight_modes.hpp),
// the inner loops (plant/flight_controller.hpp) and the mixer (plant/mixer.hpp).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "plant/dynamics.hpp"
#include "plant/flight_controller.hpp"
#include "plant/flight_modes.hpp"
#include "plant/params.hpp"
#include "plant/sdk_interpreter.hpp"
#include "plant/tello_senses.hpp"
#include "shelfcross/sdk_messages.hpp"
#include "shelfcross/time.hpp"

namespace shelfcross::plant {

class Autopilot {
 public:
  /// Throws std::invalid_argument for a non-integer or non-positive rate or bad gains.
  Autopilot(const AutopilotParams& params, const VehicleParams& vehicle, TelloSenses senses);

  /// One command datagram received at t_ns. Returns the immediate reply, if any; manoeuvres
  /// answer later through take_replies().
  std::optional<std::string> on_command(TimeNs t_ns, std::string_view text);
  /// One inner-loop tick at t_ns with the vehicle's true state, which the firmware senses
  /// (TelloSenses::sense): returns the rotor speed commands (rad/s), to be held until the next
  /// tick.
  Eigen::Vector4d update(TimeNs t_ns, const RigidBodyState& state);
  /// Deferred replies that became due (stamped with the tick that produced them), oldest first.
  std::vector<SdkReply> take_replies() { return modes_.take_replies(); }
  /// Why the command of the last on_command call was ignored (no reply, no effect) or refused
  /// (answered with an error), for people (`shelfcross plant` prints it).
  const std::string& last_refusal() const { return sdk_.last_refusal(); }

  FlightMode mode() const { return modes_.mode(); }
  bool sdk_mode() const { return sdk_.sdk_mode(); }
  bool stream_on() const { return sdk_.stream_on(); }
  int battery_pct() const;
  double motor_on_time_s() const { return ns_to_seconds(motor_on_ns_); }
  /// The firmware's senses (the state record reads them too).
  const TelloSenses& senses() const { return senses_; }

 private:
  /// What the read commands report now, and the senses of the last tick.
  DroneReadout readout() const;

  AutopilotParams params_;
  VehicleParams vehicle_;
  TelloSenses senses_;
  SdkInterpreter sdk_;
  FlightModes modes_;
  FlightController controller_;
  SensedState sensed_;  ///< at the last tick
  std::optional<TimeNs> last_update_ns_;
  RigidBodyState last_state_;
  Eigen::Vector3d specific_force_B_ = Eigen::Vector3d(0.0, 0.0, kStandardGravity_mps2);
  TimeNs last_command_ns_ = 0;
  TimeNs motor_on_ns_ = 0;
};

}  // namespace shelfcross::plant

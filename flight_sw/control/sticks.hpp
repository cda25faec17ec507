#pragma once
// What the mission flies: the velocity command (body frame, control.hpp), the vertical and
// heading PI loops that produce part of it (eq. 12, eq. 15), and the rc datagrams that carry
// it at rc_period_s (and at once when forced), at the scale the Tello's measured answer sets
// (stick_response.hpp). Time is the mission's (the stamp of the input
// being handled); nothing here reads a clock.

#include <optional>

#include "flight_sw/config.hpp"
#include "flight_sw/control/control.hpp"
#include "flight_sw/control/stick_response.hpp"
#include "shelfcross/sdk_messages.hpp"

namespace shelfcross::flight_sw {

class Sticks {
 public:
  /// The PI gains and limits of control.kp_z... and the rc conversion; `config` must be valid
  /// (validate_flight_config).
  explicit Sticks(const FlightConfig& config);

  /// Flies `v` from `now_ns` on (the time hold_or_hover counts from).
  void set(const VelocityCommand& v, TimeNs now_ns);
  /// Flies the open-loop line `v` (the crossing): as set, and its horizontal sticks carry their
  /// rounding (to_rc_carried) until the next set, hover or zeroing hold_or_hover.
  void fly_line(const VelocityCommand& v, TimeNs now_ns);
  /// Zero velocity, the PI loops restarted.
  void hover();
  /// The PI loops restarted (their integrals to 0), the command kept.
  void restart_loops();
  /// A picture that cannot steer: the last command is held over a gap of up to
  /// control.unsteered_hold_s after it was set, then zero velocity (the PI states are kept).
  /// `leaving` (the corner tags at the picture's border): zero at once.
  void hold_or_hover(TimeNs now_ns, bool leaving);
  /// The vertical (eq. 12) and heading (eq. 15) loops stepped by dt_s on e_z_m and e_psi_rad:
  /// the command's vz_mps and yaw_rate_radps (the rest zero).
  VelocityCommand steer(double e_z_m, double e_psi_rad, double dt_s);

  const VelocityCommand& velocity() const { return velocity_; }
  /// The crossing's height hold and the stale-state rule change the vertical stick alone.
  void set_vz(double vz_mps) { velocity_.vz_mps = vz_mps; }

  /// The control step's dt: the time since the last picture that steered (0 for the first),
  /// at most control.max_control_dt_s.
  double control_dt_s(TimeNs now_ns) const;
  /// A picture steered the loops at now_ns.
  void controlled(TimeNs now_ns) { last_control_ns_ = now_ns; }

  /// The rc sticks of the command, when an rc datagram is due: `force`, or rc.rc_period_s since
  /// the last (the caller sends it, stamped now_ns).
  std::optional<RcSticks> due(TimeNs now_ns, bool force);
  /// The keep-alive: no rc datagram for rc.keepalive_s.
  bool keepalive_due(TimeNs now_ns) const;
  /// A state record: what the sticks sent have done (StickResponse).
  void on_state(const StateRecord& s) { response_.on_state(s); }
  /// How strongly the Tello answers the sticks, and the scale they are sent at.
  const StickResponse& response() const { return response_; }

 private:
  ControlGains gains_;
  RcConversion rc_;
  StickResponse response_;  ///< the sticks scaled by the measured answer (due)
  PiController pi_z_, pi_psi_;
  VelocityCommand velocity_;
  std::optional<TimeNs> set_ns_;  ///< when set() last set velocity_ (hold_or_hover)
  std::optional<StickCarry> carry_;  ///< flying a line (fly_line): the horizontal sticks' rounding carried
  std::optional<TimeNs> last_rc_ns_;
  std::optional<TimeNs> last_control_ns_;
};

}  // namespace shelfcross::flight_sw

#pragma once
// Control laws (paper section 4-4, docs/method.md section 4) and the conversion of SI velocity
// commands to the SDK's rc sticks.
//
// Commands are in the body frame B (x forward, y left, z up) and yaw rate counter-clockwise
// positive seen from above. The SDK's `rc a b c d` is a right, b forward, c up, d clockwise:
//   a = -k_h * vy_B,  b = k_h * vx_B,  c = k_v * vz,  d = -k_psi * yaw_rate,
// each rounded to the nearest integer and saturated to -100..100.

#include <string>

#include "flight_sw/config.hpp"

namespace shelfcross::flight_sw {

struct PiGains {
  double kp = 0.0;
  double ki = 0.0;
  double integral_limit = 0.0;  ///< |integral of the error| never exceeds this
  double output_limit = 0.0;    ///< |output| saturates here
};

/// u = kp e + ki integral(e dt), saturated to +-output_limit. Anti-windup: the integral is
/// clamped to +-integral_limit and is not advanced while the output is saturated in the
/// direction the error pushes it (conditional integration), so that the loop leaves
/// saturation as soon as the error changes sign.
class PiController {
 public:
  PiController() = default;
  explicit PiController(PiGains gains) : gains_(gains) {}
  double update(double error, double dt_s);
  void reset() { integral_ = 0.0; }
  double integral() const { return integral_; }

 private:
  PiGains gains_;
  double integral_ = 0.0;
};

/// The lateral law of paper Fig. 19: +speed if psi > threshold, -speed if psi < -threshold,
/// 0 otherwise. psi is the heading relative to the cell normal (CCW positive) and the result
/// a body-frame y velocity (left positive); see FlightSoftware for why this sign straightens
/// the path onto the normal.
double bang_off_bang(double psi_rad, double threshold_rad, double speed_mps);

/// The crossing's height hold on the state record's height (the Tello's h, its take-off-point
/// height, in the frame the cell's height was measured in): vz = kp (target - h), saturated to
/// +-speed_max (m/s, up positive). Proportional only: the autopilot holds its own height
/// reference at zero stick, so no integral is needed to hold a height, and a crossing lasts a
/// few seconds. Not the ToF: under the vehicle in a cell are the beam and the boxes below, not
/// the floor.
double height_hold_vz_mps(double target_height_m, double height_m, double kp, double speed_max_mps);

/// A velocity command in the body frame.
struct VelocityCommand {
  double vx_B_mps = 0.0;
  double vy_B_mps = 0.0;
  double vz_mps = 0.0;
  double yaw_rate_radps = 0.0;  ///< counter-clockwise positive
  bool operator==(const VelocityCommand&) const = default;
};

struct RcSticks {
  int a = 0;  ///< right
  int b = 0;  ///< forward
  int c = 0;  ///< up
  int d = 0;  ///< clockwise
  std::string text() const;  ///< "rc a b c d"
  bool operator==(const RcSticks&) const = default;
};

/// Converts through the configured gains, rounding half away from zero, saturating to 100.
RcSticks to_rc(const VelocityCommand& v, const RcConversion& conversion);

/// The rounding each horizontal stick left out so far (rc units): a, b.
struct StickCarry {
  double a = 0.0;
  double b = 0.0;
};

/// As to_rc, but the horizontal sticks carry their rounding from datagram to datagram (error
/// diffusion): each is the rounded sum of its exact value and `carry`, and `carry` keeps what
/// that rounding left out. Over successive datagrams the sticks then average the exact command,
/// where plain rounding sends the same error every time: the crossing's 0.4 m/s line with a
/// 1.9 cm/m aim asks for 0.76 of a stick sideways, which rounds to 1 (32 % too much), and that
/// error, held for the whole blind crossing, moves the vehicle off its line (docs/method.md
/// section 7, "The line's sticks").
RcSticks to_rc_carried(const VelocityCommand& v, const RcConversion& conversion, StickCarry& carry);

}  // namespace shelfcross::flight_sw

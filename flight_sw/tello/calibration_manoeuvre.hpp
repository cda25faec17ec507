#pragma once
// The calibration manoeuvre of tello_pilot --fly-calibration: a short excitation of each stick
// axis in turn, so that a flight log identifies the drone's response (shelfcross identify,
// docs/calibration.md). For each axis, pulses alternating in sign with a hover after each:
// forward, right and up two pairs, yaw one pair (forward and lateral velocities arrive at the
// SDK's coarse 0.1 m/s, the height in cm and the heading in degrees: the velocities need more
// edges). Pulse amplitudes run from 0.8 A to 1.2 A over an axis's pulses, so that the plateaus
// fall at different places between the SDK's steps. Hovers let each response settle before
// the next: no two axes move at once. About 48 s after the takeoff.
//
// Amplitudes stay well inside the SDK's -100..100 and inside what the Tello's slow mode can
// follow without saturating its 9 deg tilt: a horizontal step of 1.2 A asks for an
// acceleration of 1.2 K A / tau, which at A = 28 is 1.40 m/s^2 for the fastest, strongest drone
// of the plausible range (K 1.25 m/s, tau 0.3 s), under the tilt limit's g tan 9 deg = 1.55 m/s^2.
// Space needed (at K = 1.25): about 0.9 m each way forward, back, left and right of the
// take-off point, 0.6 m above the take-off height and 0.2 m below it, a turn of 105 deg each way.

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace shelfcross::tello {

struct ManoeuvreStep {
  double duration_s = 0.0;
  std::array<int, 4> sticks{};  ///< rc a b c d (SDK signs: right, forward, up, clockwise)
  std::string what;             ///< for people and the log
};

struct CalibrationAmplitudes {
  int horizontal = 28;  ///< forward and lateral sticks (pulses 0.8 to 1.2 times)
  int vertical = 30;
  int yaw = 40;
};

class CalibrationManoeuvre {
 public:
  explicit CalibrationManoeuvre(const CalibrationAmplitudes& amplitudes = {});
  const std::vector<ManoeuvreStep>& steps() const { return steps_; }
  double duration_s() const;
  /// The step flown `t_s` seconds after the start (steps in order), nothing after the end.
  const ManoeuvreStep* step_at(double t_s) const;

 private:
  std::vector<ManoeuvreStep> steps_;
};

}  // namespace shelfcross::tello

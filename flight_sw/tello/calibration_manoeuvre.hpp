#pragma once
// The calibration manoeuvre of tello_pilot --fly-calibration: a short excitation of each stick
// axis, so that a flight log identifies the drone's response (shelfcross identify,
// docs/calibration.md). Two blocks, each interleaving two axes so that one axis's settling is
// the other's pulse (only one stick ever moves; every pulse or doublet is followed by centred
// sticks, and each axis has at least 2.5 s, over 3.5 time constants of the slowest plausible
// drone, between its own edges):
//   horizontal: forward and right pulses of 2 s in turn, 0.5 s of hover after each, signs
//     alternating, four per axis (forward and lateral velocities arrive at the SDK's coarse
//     0.1 m/s: they need the long plateaus and several edges);
//   height and heading: doublets (+A for 1 s, then -A for 1 s: three edges, the middle one of
//     2A, and back where it began) of the up and of the clockwise stick in turn, 0.5 s of hover
//     after each, five per axis. Height and heading arrive in cm and degrees and are fitted
//     through their integrals: a time constant shows as the lag K A tau each edge leaves, so the
//     information on it grows with the sum of the edges' squared steps, 6 A^2 for a doublet
//     against 2 A^2 for a pulse of the same amplitude and nearly the same time. Height doublets
//     all go up first (the drone never sinks below the take-off height); heading doublets
//     alternate (clockwise first, then counter-clockwise first).
// Amplitudes run from 0.8 A to 1.2 A over an axis's pulses, so that the velocity plateaus fall
// at different places between the SDK's steps. About 47.5 s after the takeoff.
//
// Amplitudes stay well inside the SDK's -100..100 and inside what the Tello's slow mode can
// follow without saturating: a horizontal step of 1.2 A asks for an acceleration of
// 1.2 K A / tau, which at A = 28 is 1.40 m/s^2 for the fastest, strongest drone of the
// plausible range (K 1.25 m/s, tau 0.3 s), under the tilt limit's g tan 9 deg = 1.55 m/s^2 (the
// other horizontal axis has then decayed for 0.5 s: at most 0.26 m/s^2 more, 1.42 in all). The
// height doublet's reversal (2.4 A = 0.96 at A = 40) asks at most 1.25 * 0.96 / 0.25 = 4.8 m/s^2
// of thrust change, under the 9.8 m/s^2 a thrust-to-weight of 2 gives and the about 8.8 m/s^2
// down to idle; the heading's (2.4 A = 1.2 at A = 50) a rate of at most 1.875 * 0.6 = 1.13 rad/s
// each way, under the autopilot's 3 rad/s; its reversal's angular acceleration, about 10 rad/s^2
// for the strongest, fastest heading of the range, is what a tello-sim drone of rc_gain_scale
// 1.18 answered with 2 to 3 cm of height during the two largest doublets (docs/calibration.md,
// section 5): a smaller heading amplitude is the margin, at the heading's resolution's cost.
// Space needed (at K = 1.25 m/s, 1.875 rad/s): about 0.9 m each way forward, back, left and
// right of the take-off point, 0.6 m above the take-off height, a turn of 65 deg each way.
//
// The senses block (CalibrationSenses, when a board's distance is stated), flown first, right
// after the first hover, so that the drone's own drift has had the least time to carry it off
// its path: a still hover of 15 s (every stick centred: the scatter of vgx, vgy, h, baro and tof
// about their slow wander is the readings' noise), then backward at stick 20 (0.2 m/s at the
// nominal 1 m/s at full stick) for distance / 0.2 m/s, so that the drone stops over the middle
// of a board of known height lying straight behind the take-off point; 8 s of hover over it
// (four time constants of the slowest height hold the scenarios draw, 2 s), forward at stick 20
// as long, back over the take-off point, and 2.5 s of hover before the pulses. Backward, so that
// the camera never faces the board. The range reading steps by the board's height as the drone
// passes its edge, in and out; how the height hold answers those steps identifies it
// (`shelfcross identify`, docs/calibration.md). A drone of 0.8 to 1.25 times the nominal gain
// stops 0.8 to 1.25 times the distance back: the board must reach that far on both sides of its
// middle (docs/calibration.md gives its size). The pass's step of 0.2 m/s asks 0.83 m/s^2 of the
// strongest, fastest drone, well inside the slow mode's tilt.

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
  int vertical = 40;    ///< up stick (doublets 0.8 to 1.2 times)
  int yaw = 50;         ///< clockwise stick (doublets 0.8 to 1.2 times)
};

/// The senses block's board: the distance from the take-off point straight back to the board's
/// middle, along the path.
struct CalibrationSenses {
  double board_distance_m = 1.5;
};

class CalibrationManoeuvre {
 public:
  /// The senses block's limits on the board's distance (m): at least a drone's length beyond the
  /// take-off point's own excursions, at most what 0.2 m/s covers in 12.5 s.
  static constexpr double kBoardDistanceMin_m = 1.0, kBoardDistanceMax_m = 2.5;
  /// The senses block's still hover (s) and the pass's stick.
  static constexpr double kStillHover_s = 15.0;
  static constexpr int kPassStick = 20;

  /// Throws std::invalid_argument when an amplitude lies outside 5..80 (its pulses reach 1.2
  /// times it, within the sticks' 100) or the board's distance outside its limits.
  explicit CalibrationManoeuvre(const CalibrationAmplitudes& amplitudes = {},
                                const std::optional<CalibrationSenses>& senses = std::nullopt);
  const std::vector<ManoeuvreStep>& steps() const { return steps_; }
  double duration_s() const;
  /// The step flown `t_s` seconds after the start (steps in order), nothing after the end.
  const ManoeuvreStep* step_at(double t_s) const;

 private:
  std::vector<ManoeuvreStep> steps_;
};

}  // namespace shelfcross::tello
